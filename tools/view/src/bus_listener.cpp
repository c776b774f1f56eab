// BusListener: LCM on a thread of its own, every message handed to the model as raw bytes (the
// model decodes with the checked decoders; LCM's typed handlers would decode unchecked).
#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <lcm/lcm-cpp.hpp>

#include "swf/view/live_view.hpp"

namespace swf::view {
namespace {

// The raw handler's trampoline: LCM calls it with the listener it was subscribed with.
class Trampoline {
 public:
  explicit Trampoline(BusListener* listener) : listener_(listener) {}
  void Handle(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    listener_->OnMessage(buffer->data, buffer->data_size, channel);
  }

 private:
  BusListener* listener_;
};

// Moves the calling thread (only it: a network namespace is per thread) into the namespace at
// `path`, so that its sockets are opened there. "" with success, else the reason.
std::string JoinNetworkNamespace(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return "cannot open network namespace " + path + ": " + std::strerror(errno);
  const int rc = setns(fd, CLONE_NEWNET);
  const int saved = errno;
  close(fd);
  if (rc != 0) return "cannot join network namespace " + path + ": " + std::strerror(saved);
  return "";
}

}  // namespace

BusListener::BusListener(LiveModel* model) : model_(model) {}
BusListener::~BusListener() { Stop(); }

void BusListener::OnMessage(const void* data, std::size_t size, const std::string& channel) {
  messages_.fetch_add(1, std::memory_order_relaxed);
  model_->Ingest(channel, data, size);
}

bool BusListener::Start(const std::string& lcm_url, const std::string& channel_regex,
                        const std::string& netns_path, std::string* error) {
  quit_.store(false);
  started_.store(0);
  thread_ = std::thread(&BusListener::Run, this, lcm_url, channel_regex, netns_path);
  while (started_.load() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (started_.load() < 0) {
    thread_.join();
    std::lock_guard<std::mutex> lock(error_mutex_);
    *error = error_;
    return false;
  }
  return true;
}

void BusListener::Run(std::string lcm_url, std::string channel_regex, std::string netns_path) {
  const auto fail = [this](const std::string& why) {
    std::lock_guard<std::mutex> lock(error_mutex_);
    error_ = why;
    started_.store(-1);
  };
  if (!netns_path.empty()) {
    const std::string why = JoinNetworkNamespace(netns_path);
    if (!why.empty()) return fail(why);
  }
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    return fail("cannot open LCM at " + lcm_url + " (a multicast route? docs RECIPES.md)");
  }
  Trampoline trampoline(this);
  lcm.subscribe(channel_regex, &Trampoline::Handle, &trampoline);
  started_.store(1);
  while (!quit_.load()) lcm.handleTimeout(100);
}

void BusListener::Stop() {
  quit_.store(true);
  if (thread_.joinable()) thread_.join();
}

}  // namespace swf::view
