// ViewServer: cpp-httplib serving the page, the state and one server-sent event stream per client.
#include <httplib.h>

#include <algorithm>

#include "swf/view/live_view.hpp"

namespace swf::view {
namespace {

using Clock = std::chrono::steady_clock;

// One browser's stream: what it has been sent, so that it gets only what changed, and when.
struct ClientStream {
  std::uint64_t sent_version[LiveModel::kNumParts] = {};
  bool sent_once[LiveModel::kNumParts] = {};
  Clock::time_point last_sent[LiveModel::kNumParts] = {};
  std::uint64_t seen_sum = ~std::uint64_t{0};
  Clock::time_point last_round;
};

// The least time between two sends of a part to one client: the status is resent each second
// even unchanged (it says how long the publisher has been silent), images are paced apart.
std::chrono::milliseconds MinInterval(LiveModel::Part part) {
  if (part == LiveModel::kImage) return std::chrono::milliseconds(1000 / kMaxImageHz);
  return std::chrono::milliseconds(1000 / kMaxEventHz);
}

bool WriteEvent(httplib::DataSink& sink, const char* name, const std::string& data,
                LiveModel* model) {
  std::string event = "event: ";
  event += name;
  event += "\ndata: ";
  event += data;
  event += "\n\n";
  if (!sink.write(event.data(), event.size())) return false;
  model->CountEventsSent(static_cast<std::int64_t>(event.size()));
  return true;
}

}  // namespace

struct ViewServer::Impl {
  explicit Impl(LiveModel* m) : model(m) {}

  // One round of a client's stream: waits for something new (at most a second), then sends
  // each part that changed and is due. False when the client is gone or the server stops.
  bool StreamRound(ClientStream* client, httplib::DataSink& sink) {
    if (stopping.load()) return false;
    // Pace the client: at most kMaxEventHz rounds a second, whatever the bus does.
    const auto next_round = client->last_round + std::chrono::milliseconds(1000 / kMaxEventHz);
    const auto now_before = Clock::now();
    if (next_round > now_before) std::this_thread::sleep_for(next_round - now_before);
    client->seen_sum = model->WaitForChange(client->seen_sum, std::chrono::milliseconds(1000));
    client->last_round = Clock::now();
    if (stopping.load()) return false;
    for (int p = 0; p < LiveModel::kNumParts; ++p) {
      const auto part = static_cast<LiveModel::Part>(p);
      const std::uint64_t version = model->Version(part);
      const bool changed = !client->sent_once[p] || version != client->sent_version[p];
      const bool heartbeat = part == LiveModel::kStatus &&
                             client->last_round - client->last_sent[p] >= std::chrono::seconds(1);
      if (!changed && !heartbeat) continue;
      if (client->sent_once[p] && client->last_round - client->last_sent[p] < MinInterval(part)) {
        continue;  // not due yet: the newest version goes next round (latest wins)
      }
      if (!WriteEvent(sink, LiveModel::PartName(part), *model->Json(part), model)) return false;
      if (part == LiveModel::kImage) model->MarkImageServed(version);
      client->sent_version[p] = version;
      client->sent_once[p] = true;
      client->last_sent[p] = client->last_round;
    }
    // Something may be due but held back by pacing: come back next round instead of waiting.
    client->seen_sum = ~std::uint64_t{0};
    for (int p = 0; p < LiveModel::kNumParts; ++p) {
      if (client->sent_version[p] != model->Version(static_cast<LiveModel::Part>(p))) return true;
    }
    client->seen_sum = model->VersionSum();
    return true;
  }

  void Routes() {
    server.Get("/", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(PageHtml(), "text/html; charset=utf-8");
    });
    server.Get("/state.json", [this](const httplib::Request&, httplib::Response& res) {
      res.set_header("Cache-Control", "no-store");
      res.set_content(model->StateJson(), "application/json");
    });
    server.Get("/healthz", [](const httplib::Request&, httplib::Response& res) {
      res.set_content("ok\n", "text/plain");
    });
    server.Get("/events", [this](const httplib::Request&, httplib::Response& res) {
      // Each stream holds one of the server's threads: bounded, so the page and the state
      // always have threads left.
      if (clients.fetch_add(1) >= kMaxClients) {
        clients.fetch_sub(1);
        model->CountClientRefused();
        res.status = 503;
        res.set_content("too many event streams\n", "text/plain");
        return;
      }
      model->CountClient(+1);
      res.set_header("Cache-Control", "no-store");
      auto client = std::make_shared<ClientStream>();
      res.set_chunked_content_provider(
          "text/event-stream",
          [this, client](std::size_t, httplib::DataSink& sink) {
            return StreamRound(client.get(), sink);
          },
          [this](bool) {
            clients.fetch_sub(1);
            model->CountClient(-1);
          });
    });
  }

  LiveModel* model;
  httplib::Server server;
  std::atomic<bool> stopping{false};
  std::atomic<int> clients{0};
  std::thread thread;
};

ViewServer::ViewServer(LiveModel* model) : impl_(std::make_unique<Impl>(model)) {}
ViewServer::~ViewServer() { Stop(); }

bool ViewServer::Start(const std::string& host, int port, std::string* error) {
  impl_->Routes();
  // A stalled client must not hold a thread for long.
  impl_->server.set_write_timeout(std::chrono::seconds(5));
  impl_->server.set_read_timeout(std::chrono::seconds(5));
  if (port == 0) {
    port_ = impl_->server.bind_to_any_port(host);
    if (port_ <= 0) {
      *error = "cannot bind to any port on " + host;
      return false;
    }
  } else {
    if (!impl_->server.bind_to_port(host, port)) {
      *error = "cannot bind to " + host + ":" + std::to_string(port) + " (in use?)";
      return false;
    }
    port_ = port;
  }
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
  return true;
}

void ViewServer::Stop() {
  if (!impl_ || !impl_->thread.joinable()) return;
  impl_->stopping.store(true);
  impl_->server.stop();
  impl_->thread.join();
}

}  // namespace swf::view
