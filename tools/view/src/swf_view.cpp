// swf-view: the live view of a descent. Listens to the flight process's LCM outputs (swf-sil,
// swf-replay, swf-fsw: a subscriber only, it never slows them) and serves a page that redraws as
// they arrive. At exit (SIGINT, SIGTERM, --timeout) prints its counters as one JSON object.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "swf/ground_cli/ground_cli.hpp"
#include "swf/view/live_view.hpp"

namespace {

std::atomic<bool> g_stop{false};

void OnSignal(int) { g_stop.store(true); }

struct Arguments {
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  std::string lcm_netns;
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string url_file;
  double timeout_s = 0.0;
  swf::view::ViewOptions view;
};

// The final counters (what a test or a log keeps of the run).
std::string SummaryJson(swf::view::LiveModel* model, const swf::view::BusListener& bus,
                        const nlohmann::json& run) {
  nlohmann::json status = nlohmann::json::parse(*model->Json(swf::view::LiveModel::kStatus));
  nlohmann::json out = {{"messages", bus.Messages()},
                        {"frames", status["frames"]},
                        {"bus", status["bus"]},
                        {"http", status["http"]},
                        {"run", run}};
  return out.dump();
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app{
      "swf-view: a live web view of the flight process's LCM outputs (image, trajectory, "
      "landmarks, hazard map, integrity, health)"};
  swf::ground_cli::Adopt(&app, "swf-view");
  app.add_option("--lcm-url", args.lcm_url, "LCM URL to listen on")->capture_default_str();
  app.add_option("--lcm-netns", args.lcm_netns,
                 "listen to LCM inside this network namespace (/run/netns/NAME, "
                 "/proc/PID/ns/net) while serving the page in this one");
  app.add_option("--prefix", args.view.prefix, "the flight process's lcm.channel_prefix")
      ->capture_default_str();
  app.add_option("--truth-prefix", args.view.truth_prefix, "the simulator's truth channel")
      ->capture_default_str();
  app.add_option("--host", args.host, "address to serve on")->capture_default_str();
  app.add_option("--port", args.port, "port to serve on (0: any free port)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  app.add_option("--url-file", args.url_file, "write the page's URL to this file once serving");
  app.add_option("--max-image-width", args.view.max_image_width_px,
                 "decimate the left image to at most this width, px")
      ->capture_default_str()
      ->check(CLI::Range(16, 4096));
  app.add_option("--timeout", args.timeout_s, "exit after this many seconds (0: run until signal)")
      ->check(CLI::NonNegativeNumber);
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }

  swf::view::LiveModel model(args.view);
  swf::view::BusListener bus(&model);
  std::string error;
  // Every channel of the flight process and the truth; the model ignores (and counts) the rest.
  const std::string regex = args.view.prefix + ".*|" + args.view.truth_prefix + ".*";
  if (!bus.Start(args.lcm_url, regex, args.lcm_netns, &error)) {
    std::fprintf(stderr, "swf-view: %s\n", error.c_str());
    return 1;
  }
  swf::view::ViewServer server(&model);
  if (!server.Start(args.host, args.port, &error)) {
    std::fprintf(stderr, "swf-view: %s\n", error.c_str());
    return 1;
  }
  const std::string url = "http://" + args.host + ":" + std::to_string(server.Port()) + "/";
  std::fprintf(stderr, "swf-view: serving %s (listening on %s, %s*)\n", url.c_str(),
               args.lcm_url.c_str(), args.view.prefix.c_str());
  if (!args.url_file.empty() && !swf::cli::WriteFileAtomically(args.url_file, url + "\n", &error)) {
    std::fprintf(stderr, "swf-view: %s\n", error.c_str());
    server.Stop();
    bus.Stop();
    return swf::cli::kExitFailed;
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);  // a browser closing its stream is a write error, not a death
  const auto start = std::chrono::steady_clock::now();
  while (!g_stop.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (args.timeout_s > 0.0 && elapsed > args.timeout_s) break;
  }
  server.Stop();
  bus.Stop();
  std::printf(
      "%s\n",
      SummaryJson(&model, bus, swf::ground_cli::RunEcho(app, "swf-view", argc, argv)).c_str());
  return 0;
}
