// swf::view: the live view of a descent (swf-view). A ground process that listens to the flight
// process's LCM outputs like swf-guidance does (a subscriber only: it never sends anything the
// flight process waits for) and serves one self-contained web page that redraws as they arrive.
//
// Three parts, each usable alone (the tests drive each one):
//   LiveModel    what the page shows: every message on a watched channel goes through the checked
//                decoders (swf/messages/checked_decode.hpp); what does not decode is counted and
//                reported, never fatal. Holds the newest of each kind (latest wins) and a bounded
//                trajectory history, and renders each part as JSON (never inf or nan).
//   BusListener  one thread receiving LCM into the model (optionally inside another network
//                namespace, so the page can be served on the host while the flight process
//                publishes in a private one).
//   ViewServer   the HTTP side (cpp-httplib): the page, /state.json, and /events, a server-sent
//                event stream per client. Each client is paced on its own (at most kMaxEventHz
//                updates a second, newest state only), so a slow browser skips states and never
//                holds up the bus thread; the number of clients is bounded.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace swf::view {

// What a channel's traffic looked like (sequence numbers as swf-guidance checks them).
struct ChannelCounters {
  std::int64_t received = 0;      // decoded and accepted
  std::int64_t malformed = 0;     // refused by the checked decoder (or a negative sequence)
  std::int64_t lost = 0;          // missing sequence numbers (dropped on the way: bus or kernel)
  std::int64_t out_of_order = 0;  // a sequence number at or below the previous one
  std::int64_t restarts = 0;      // the publisher started again (sequence back to 0)
  std::int64_t next_seq = -1;     // -1: nothing yet
};

struct ViewOptions {
  std::string prefix = "SWF_";             // the flight process's lcm.channel_prefix
  std::string truth_prefix = "SIM_TRUTH";  // the simulator's truth channels, when on the bus
  int max_image_width_px = 512;            // the left image is decimated to at most this
  int trajectory_points = 4000;            // the history the page draws (oldest dropped)
};

// The newest state of the descent, fed message by message from one thread (the bus thread) and
// read from any number of others (the HTTP clients). Every method is thread-safe.
class LiveModel {
 public:
  explicit LiveModel(ViewOptions options = {});
  ~LiveModel();
  LiveModel(const LiveModel&) = delete;
  LiveModel& operator=(const LiveModel&) = delete;

  // One message as it came off the bus. Channels the view does not know are ignored (counted as
  // "ignored"); a known channel's bytes that do not decode are counted as malformed.
  void Ingest(const std::string& channel, const void* data, std::size_t size);

  // The page's parts as JSON text. Each part has a version that changes when it changes, so a
  // client sends only what is new; the text is built once per version and shared.
  enum Part : int { kStatus = 0, kTrajectory, kLandmarks, kHazard, kImage, kFeatures, kNumParts };
  static const char* PartName(Part part);
  std::uint64_t Version(Part part) const;
  std::shared_ptr<const std::string> Json(Part part);
  // Every part in one object (/state.json and the tests).
  std::string StateJson();

  // Blocks until any part changes past `seen` (the sum of versions) or `timeout` passes; returns
  // the sum of versions now.
  std::uint64_t WaitForChange(std::uint64_t seen, std::chrono::milliseconds timeout);
  std::uint64_t VersionSum() const;
  // A client saw image version `version`: images overwritten before anyone saw them are counted
  // as superseded (latest wins: the view never queues frames).
  void MarkImageServed(std::uint64_t version);
  // The HTTP side's own counts, shown with the bus counts.
  void CountClient(int delta);
  void CountClientRefused();
  void CountEventsSent(std::int64_t bytes);

  ChannelCounters Counters(const std::string& channel_suffix) const;
  std::int64_t MalformedTotal() const;
  std::int64_t LostTotal() const;
  std::int64_t ImagesSuperseded() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Receives the flight process's channels into a model on a thread of its own.
class BusListener {
 public:
  explicit BusListener(LiveModel* model);
  ~BusListener();
  BusListener(const BusListener&) = delete;
  BusListener& operator=(const BusListener&) = delete;

  // netns_path: "" = this process's network namespace; else a namespace file (/run/netns/NAME,
  // /proc/PID/ns/net) that the listening thread joins before it opens LCM. False with a message.
  bool Start(const std::string& lcm_url, const std::string& channel_regex,
             const std::string& netns_path, std::string* error);
  void Stop();
  std::int64_t Messages() const { return messages_.load(); }

  // Raw LCM handler (this LCM version does not take lambdas).
  void OnMessage(const void* data, std::size_t size, const std::string& channel);

 private:
  void Run(std::string lcm_url, std::string channel_regex, std::string netns_path);

  LiveModel* model_;
  std::atomic<bool> quit_{false};
  std::atomic<int> started_{0};  // 0 starting, 1 listening, -1 failed
  std::atomic<std::int64_t> messages_{0};
  std::mutex error_mutex_;
  std::string error_;
  std::thread thread_;
};

// The page served with the binary (page.html, embedded at build time).
const std::string& PageHtml();

inline constexpr int kMaxEventHz = 10;  // state updates a second per client, at most
inline constexpr int kMaxImageHz = 5;   // images a second per client, at most
inline constexpr int kMaxClients = 6;   // event streams at once (each holds a server thread)

class ViewServer {
 public:
  explicit ViewServer(LiveModel* model);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  // Binds (port 0: any free port) and serves on a thread of its own. False with a message.
  bool Start(const std::string& host, int port, std::string* error);
  int Port() const { return port_; }
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int port_ = 0;
};

}  // namespace swf::view
