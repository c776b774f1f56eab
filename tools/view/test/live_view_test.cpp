// swf::view unit tests: the model's counting and latest-wins rule, its JSON, and the server's
// endpoints on a real socket (the bus and the browser are exercised by the scripts beside this).
#include <httplib.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "gtest/gtest.h"
#include "swf/view/live_view.hpp"
#include "swf_msgs/feature_set_t.hpp"
#include "swf_msgs/hazard_map_t.hpp"
#include "swf_msgs/nav_state_t.hpp"
#include "swf_msgs/stereo_frame_t.hpp"
#include "swf_msgs/truth_state_t.hpp"

namespace swf::view {
namespace {

template <typename Msg>
std::vector<std::uint8_t> Encode(const Msg& msg) {
  std::vector<std::uint8_t> bytes(msg.getEncodedSize());
  EXPECT_GT(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  return bytes;
}

void Send(LiveModel* model, const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  model->Ingest(channel, bytes.data(), bytes.size());
}

swf_msgs::nav_state_t Nav(std::int64_t seq) {
  swf_msgs::nav_state_t n{};
  n.seq = seq;
  n.frame_seq = seq;
  n.orientation_world_q[0] = 1.0;
  n.position_world_m[2] = 100.0 - static_cast<double>(seq);
  return n;
}

swf_msgs::stereo_frame_t Frame(std::int64_t seq, int width, int height) {
  swf_msgs::stereo_frame_t f{};
  f.seq = seq;
  f.rectified = true;
  f.width = width;
  f.height = height;
  f.num_bytes = width * height;
  f.left.assign(f.num_bytes, 200);
  f.right.assign(f.num_bytes, 100);
  return f;
}

nlohmann::json State(LiveModel* model) { return nlohmann::json::parse(model->StateJson()); }

TEST(LiveModel, CountsMalformedMessagesAndKeepsGoing) {
  LiveModel model;
  // GIVEN junk, a truncated message and random bytes on every channel the view decodes
  const std::vector<std::uint8_t> junk(29, 0x5A);
  std::vector<std::uint8_t> truncated = Encode(Nav(0));
  truncated.resize(truncated.size() - 3);
  Send(&model, "SWF_NAV", junk);
  Send(&model, "SWF_NAV", truncated);
  std::mt19937 rng(7);
  int random_sent = 0;
  for (const char* channel : {"SWF_NAV", "SWF_LANDMARKS", "SWF_HAZARD", "SWF_HEALTH", "SWF_STEREO",
                              "SIM_TRUTH", "SIM_TRUTH_LANDMARKS"}) {
    for (int i = 0; i < 50; ++i) {
      std::vector<std::uint8_t> bytes(rng() % 300);
      for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
      Send(&model, channel, bytes);
      ++random_sent;
    }
  }
  // WHEN a good message follows
  Send(&model, "SWF_NAV", Encode(Nav(0)));
  // THEN every bad one is counted, the reason of the last is reported, the good one is shown
  EXPECT_EQ(model.MalformedTotal(), 2 + random_sent);
  const nlohmann::json state = State(&model);
  EXPECT_EQ(state["status"]["frames"], 1);
  EXPECT_EQ(state["status"]["nav"]["status"], "VALID");
  EXPECT_FALSE(state["status"]["bus"]["last_error"].get<std::string>().empty());
}

TEST(LiveModel, CountsGapsLateMessagesAndRestarts) {
  LiveModel model;
  for (std::int64_t seq : {0, 1, 2, 5, 4, 6, 0, 1}) Send(&model, "SWF_NAV", Encode(Nav(seq)));
  const ChannelCounters c = model.Counters("NAV");
  EXPECT_EQ(c.received, 7);      // all but the late 4
  EXPECT_EQ(c.lost, 2);          // 3 and 4 were missing when 5 came
  EXPECT_EQ(c.out_of_order, 1);  // 4 after 5
  EXPECT_EQ(c.restarts, 1);      // back to 0: a new flight
  // The trajectory is the new flight's only.
  const nlohmann::json state = State(&model);
  EXPECT_EQ(state["trajectory"]["frame_seq"].size(), 2u);
}

TEST(LiveModel, ImagesAreDecimatedAndTheLatestWins) {
  LiveModel model;
  Send(&model, "SWF_STEREO", Encode(Frame(0, 1024, 768)));
  Send(&model, "SWF_STEREO", Encode(Frame(1, 1024, 768)));  // nobody saw frame 0
  EXPECT_EQ(model.ImagesSuperseded(), 1);
  model.MarkImageServed(model.Version(LiveModel::kImage));
  Send(&model, "SWF_STEREO", Encode(Frame(2, 1024, 768)));  // frame 1 was seen
  EXPECT_EQ(model.ImagesSuperseded(), 1);
  const nlohmann::json image = nlohmann::json::parse(*model.Json(LiveModel::kImage));
  EXPECT_EQ(image["seq"], 2);
  EXPECT_EQ(image["width"], 512);
  EXPECT_EQ(image["height"], 384);
  EXPECT_EQ(image["source_width"], 1024);
  EXPECT_EQ(image["gray_base64"].get<std::string>().size(), 512u * 384u / 3u * 4u);
}

TEST(LiveModel, PairsTruthWithItsEstimateInEitherOrder) {
  LiveModel model;
  swf_msgs::truth_state_t truth{};
  truth.frame_seq = 0;
  truth.orientation_world_q[0] = 1.0;
  truth.position_world_m[2] = 100.5;
  Send(&model, "SIM_TRUTH", Encode(truth));  // before its estimate
  Send(&model, "SWF_NAV", Encode(Nav(0)));
  Send(&model, "SWF_NAV", Encode(Nav(1)));
  truth.frame_seq = 1;
  truth.position_world_m[2] = 99.25;
  Send(&model, "SIM_TRUTH", Encode(truth));  // after it
  const nlohmann::json state = State(&model);
  EXPECT_DOUBLE_EQ(state["trajectory"]["truth_m"][0][2].get<double>(), 100.5);
  EXPECT_DOUBLE_EQ(state["trajectory"]["truth_m"][1][2].get<double>(), 99.25);
  EXPECT_NEAR(state["status"]["truth"]["error_m"].get<double>(), 0.25, 1e-12);
}

TEST(LiveModel, ShowsFeatureSetsAndCountsUnknownStatuses) {
  LiveModel model;
  swf_msgs::feature_set_t set{};
  set.frame_seq = 3;
  set.num_features = 3;
  set.id = {1, 2, 3};
  set.u_px = {1.0f, 2.0f, 3.0f};
  set.v_px = {4.0f, 5.0f, 6.0f};
  set.status = {swf_msgs::feature_set_t::STATUS_TRACKED, swf_msgs::feature_set_t::STATUS_GATED,
                swf_msgs::feature_set_t::STATUS_TRACKED};
  Send(&model, "SWF_FEATURES", Encode(set));
  set.seq = 1;
  set.status[0] = 9;  // no such status: refused, counted, the previous set stays
  Send(&model, "SWF_FEATURES", Encode(set));
  EXPECT_EQ(model.Counters("FEATURES").malformed, 1);
  const nlohmann::json features = nlohmann::json::parse(*model.Json(LiveModel::kFeatures));
  EXPECT_EQ(features["frame_seq"], 3);
  EXPECT_EQ(features["status"], "030");
  EXPECT_EQ(features["counts"]["tracked"], 2);
  EXPECT_EQ(features["counts"]["gated"], 1);
}

TEST(LiveModel, JsonStaysValidWithNonFiniteNumbers) {
  LiveModel model;
  swf_msgs::nav_state_t nav = Nav(0);
  nav.position_world_m[0] = std::numeric_limits<double>::quiet_NaN();
  nav.horizontal_protection_m = std::numeric_limits<double>::infinity();
  Send(&model, "SWF_NAV", Encode(nav));
  swf_msgs::hazard_map_t h{};
  h.rows = h.cols = 2;
  h.num_cells = 4;
  h.up_world[2] = 1.0;
  h.cell_size_m = 1.0;
  h.elevation_m.assign(4, std::numeric_limits<float>::quiet_NaN());
  h.sigma_m.assign(4, 0.1f);
  h.relief_sigma_m.assign(4, 0.05f);
  h.slope_deg.assign(4, 0.0f);
  h.roughness_m.assign(4, 0.0f);
  h.hazard_class = {0, 1, 3, 5};
  Send(&model, "SWF_HAZARD", Encode(h));
  const std::string text = model.StateJson();
  EXPECT_EQ(text.find("nan"), std::string::npos);
  EXPECT_EQ(text.find("inf"), std::string::npos);
  const nlohmann::json state = nlohmann::json::parse(text);
  EXPECT_TRUE(state["status"]["nav"]["horizontal_protection_m"].is_null());
  EXPECT_EQ(state["hazard"]["classes"], "0135");
  EXPECT_EQ(state["hazard"]["known_cells"], 3);
}

TEST(ViewServer, ServesThePageTheStateAndAnEventStream) {
  LiveModel model;
  Send(&model, "SWF_NAV", Encode(Nav(0)));
  ViewServer server(&model);
  std::string error;
  ASSERT_TRUE(server.Start("127.0.0.1", 0, &error)) << error;
  httplib::Client client("127.0.0.1", server.Port());
  const auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("EventSource"), std::string::npos);
  // Nothing fetched from elsewhere: no external script, style or image.
  EXPECT_EQ(page->body.find("http://"), std::string::npos);
  EXPECT_EQ(page->body.find("https://"), std::string::npos);
  const auto state = client.Get("/state.json");
  ASSERT_TRUE(state);
  EXPECT_EQ(nlohmann::json::parse(state->body)["status"]["frames"], 1);
  // The stream: read until the status event arrives, then hang up.
  std::string received;
  client.Get("/events", [&](const char* data, std::size_t size) {
    received.append(data, size);
    return received.find("event: status\ndata: {") == std::string::npos;
  });
  EXPECT_NE(received.find("event: status"), std::string::npos);
  server.Stop();
}

}  // namespace
}  // namespace swf::view
