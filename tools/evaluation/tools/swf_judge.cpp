// swf-judge: judges a run from its LCM logs (navigation, landmarks, hazard maps). Every message of
// the logs goes to RunJudge (the evaluation swf-sil runs live); the estimates and the truth may
// come from different logs (a replay's output log and the simulated descent's log it replayed).
//   swf-judge RUN.lcmlog [MORE.lcmlog ...] [--json FILE] [--outputs]
// Exit (docs/cli.md): 0 judged, no VALID output beyond its protection level; 1 judged with
// integrity failures, or nothing judged (an unreadable or damaged log, no estimate with its
// truth: the report says which); 2 usage.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "swf/evaluation/run_judge.hpp"
#include "swf/ground_cli/ground_cli.hpp"

namespace {

using nlohmann::json;
using swf::evaluation::RunScore;

// A judged hazard map as the summary of swf-sil gives it.
json HazardReport(const swf::evaluation::HazardScore& h) {
  const swf::evaluation::HazardMapMetrics& m = h.map;
  json report = {{"frame", h.frame_seq},
                 {"altitude_m", h.altitude_m},
                 {"known_cells", m.known_cells},
                 {"rocks_resolved", m.rocks_resolved},
                 {"rocks_detected", m.rocks_detected},
                 {"rocks_flagged", m.rocks_flagged},
                 {"detection_probability", nullptr},
                 {"rock_free_cells", m.rock_free_cells},
                 {"false_rock_cells", m.false_rock_cells},
                 {"false_alarm_rate", m.false_alarm_rate},
                 {"site", nullptr}};
  if (m.detection_probability >= 0.0) report["detection_probability"] = m.detection_probability;
  if (m.site_valid) {
    report["site"] = {{"x_m", m.site_world_m[0]},
                      {"y_m", m.site_world_m[1]},
                      {"score", m.site_score},
                      {"clearance_to_truth_hazard_m", m.site_clearance_m},
                      {"on_truth_hazard", m.site_on_hazard}};
  }
  return report;
}

json Report(const RunScore& s, bool with_outputs) {
  json navigation = {{"outputs_judged", s.outputs.size()},
                     {"outputs_without_truth", s.navs_without_truth},
                     {"pose_rms_error_m", s.pose_rms_error_m},
                     {"final_pose_error_m", s.final_pose_error_m},
                     {"final_attitude_error_deg", s.final_attitude_error_deg},
                     {"mean_position_nees", s.mean_position_nees}};
  json integrity = {{"valid_outputs", s.valid_navs},
                    {"protection_violations", s.protection_violations},
                    {"max_error_over_protection", s.max_error_over_protection}};
  json landmarks = {{"maps_judged", s.maps.size()}, {"maps_without_truth", s.maps_without_truth}};
  if (!s.maps.empty()) {
    landmarks["last_map_frame"] = s.maps.back().frame_seq;
    landmarks["last_map_landmarks_evaluated"] = s.maps.back().landmarks_evaluated;
    landmarks["last_map_rms_error_m"] = s.maps.back().rms_error_m;
    landmarks["last_map_median_error_m"] = s.maps.back().median_error_m;
  }
  json hazard = {{"maps_judged", s.hazard_maps.size()},
                 {"maps_without_truth", s.hazard_maps_without_truth},
                 {"truth_for_another_grid", s.hazard_truth_mismatched},
                 {"last_map", nullptr}};
  if (!s.hazard_maps.empty()) hazard["last_map"] = HazardReport(s.hazard_maps.back());
  json report = {{"navigation", navigation},
                 {"integrity", integrity},
                 {"landmarks", landmarks},
                 {"hazard", hazard},
                 {"undecodable_messages", s.undecodable}};
  if (s.undecodable > 0) report["first_decode_error"] = s.first_decode_error;
  if (with_outputs) {
    json outputs = json::array();
    for (const swf::evaluation::OutputScore& o : s.outputs) {
      outputs.push_back({{"frame", o.frame_seq},
                         {"altitude_m", o.altitude_m},
                         {"error_m", o.error_m},
                         {"horizontal_error_m", o.horizontal_error_m},
                         {"vertical_error_m", o.vertical_error_m},
                         {"attitude_error_deg", o.attitude_error_deg},
                         {"status", o.status},
                         {"hpl_m", o.hpl_m},
                         {"vpl_m", o.vpl_m},
                         {"position_nees", o.position_nees}});
    }
    report["outputs"] = outputs;
    json maps = json::array();
    for (const swf::evaluation::HazardScore& h : s.hazard_maps) maps.push_back(HazardReport(h));
    report["hazard_maps"] = maps;
  }
  return report;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "swf-judge: judges a run's navigation, landmark and hazard outputs (SWF_NAV, SWF_LANDMARKS, "
      "SWF_HAZARD) against the truth recorded beside them (SIM_TRUTH, SIM_TRUTH_LANDMARKS, "
      "SIM_TRUTH_HAZARD)"};
  swf::ground_cli::Adopt(&app, "swf-judge");
  std::vector<std::string> logs;
  std::string json_path;
  bool with_outputs = false;
  swf::evaluation::JudgeChannels channels;
  app.add_option("logs", logs, "LCM logs: the run's outputs and the truth (any order)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--json", json_path, "write the report here instead of standard output");
  app.add_flag("--outputs", with_outputs, "include every judged navigation output and hazard map");
  app.add_option("--nav-channel", channels.nav, "estimates' navigation channel")
      ->capture_default_str();
  app.add_option("--landmarks-channel", channels.landmarks, "estimates' landmark channel")
      ->capture_default_str();
  app.add_option("--truth-channel", channels.truth, "truth states' channel")->capture_default_str();
  app.add_option("--truth-landmarks-channel", channels.truth_landmarks,
                 "true landmark positions' channel")
      ->capture_default_str();
  app.add_option("--hazard-channel", channels.hazard, "estimates' hazard map channel")
      ->capture_default_str();
  app.add_option("--truth-hazard-channel", channels.truth_hazard, "hazard maps' truth channel")
      ->capture_default_str();
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }

  swf::evaluation::RunJudge judge(channels);
  swf::evaluation::LogTally tally;
  if (std::string error; !swf::evaluation::JudgeLogs(logs, &judge, &tally, &error)) {
    std::fprintf(stderr, "swf-judge: %s\n", error.c_str());
    return swf::cli::kExitFailed;
  }
  const RunScore score = judge.Score();
  json report = Report(score, with_outputs);
  report["logs"] = logs;
  report["events_read"] = tally.events;
  const bool judged = !score.outputs.empty();
  const bool failed = score.protection_violations > 0;
  report["result"] = !judged ? "not judged" : (failed ? "failed" : "ok");
  if (!judged) {
    report["reason"] = score.navs_without_truth > 0
                           ? "no navigation output has the truth of its frame"
                           : "no navigation output in the logs";
  } else if (failed) {
    report["reason"] = std::to_string(score.protection_violations) +
                       " VALID outputs erred beyond their protection level";
  }
  report["run"] = swf::ground_cli::RunEcho(app, "swf-judge", argc, argv);
  if (json_path.empty()) {
    swf::ground_cli::PrintJson(report);
  } else if (std::string error; !swf::ground_cli::WriteJson(json_path, report, &error)) {
    std::fprintf(stderr, "swf-judge: %s\n", error.c_str());
    return swf::cli::kExitFailed;
  }
  std::fprintf(stderr,
               "swf-judge: %s: %zu outputs judged, pose RMS %.3f m, %lld of %lld VALID "
               "outputs beyond their protection level, %zu hazard maps judged%s\n",
               report["result"].get<std::string>().c_str(), score.outputs.size(),
               score.pose_rms_error_m, static_cast<long long>(score.protection_violations),
               static_cast<long long>(score.valid_navs), score.hazard_maps.size(),
               score.undecodable > 0 ? " (some messages did not decode: see the report)" : "");
  return judged && !failed ? swf::cli::kExitOk : swf::cli::kExitFailed;
}
