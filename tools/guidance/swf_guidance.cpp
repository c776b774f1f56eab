// swf-guidance: the guidance-side consumer of the flight process's LCM outputs. Prints every
// navigation state, landmark map, hazard map and health message (--quiet: only the summary), checks
// sequence numbers, counts malformed messages, and exits after --idle seconds without traffic (once
// something arrived) or --timeout seconds in all, printing a JSON summary on stdout.
//   swf-guidance [--url URL] [--prefix SWF_] [--idle S] [--timeout S] [--quiet]
//                [--map-out FILE]   (the last landmark map as "x y z" lines, for plotting)
#include <chrono>
#include <cstdio>
#include <string>

#include "guidance_monitor.hpp"
#include "swf/ground_cli/ground_cli.hpp"

namespace {

using nlohmann::json;
using swf::ground_cli::Number;

json Counts(const swf::guidance::ChannelStats& c, bool ordered) {
  json counts = {{"received", c.received}, {"lost", c.lost}, {"malformed", c.malformed}};
  if (ordered) counts["out_of_order"] = c.out_of_order;
  return counts;
}

}  // namespace

int main(int argc, char** argv) {
  // The receive buffer holds a whole hazard map (~1.1 MB in fragments).
  std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  std::string prefix = "SWF_";
  std::string map_out;
  double idle_s = 2.0;
  double timeout_s = 120.0;
  bool quiet = false;
  CLI::App app{
      "swf-guidance: the guidance-side consumer of the flight process's LCM outputs; prints a "
      "JSON summary on stdout at the end"};
  swf::ground_cli::Adopt(&app, "swf-guidance");
  app.add_option("--url", url, "LCM URL to listen on")->capture_default_str();
  app.add_option("--prefix", prefix, "the flight process's channel prefix")->capture_default_str();
  app.add_option("--idle", idle_s, "exit after this many seconds without traffic (once any)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--timeout", timeout_s, "exit after this many seconds in all")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_flag("--quiet", quiet, "print only the summary");
  app.add_option("--map-out", map_out, "write the last landmark map here as \"id x y z\" lines");
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "swf-guidance: cannot open LCM at %s (multicast route? RECIPES.md)\n",
                 url.c_str());
    return 1;
  }
  swf::guidance::GuidanceMonitor monitor(&lcm, prefix, !quiet);
  std::fflush(stdout);
  std::fprintf(stderr, "swf-guidance: listening on %s (%s*)\n", url.c_str(), prefix.c_str());
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last = start;
  for (;;) {
    const int r = lcm.handleTimeout(100);
    const auto now = Clock::now();
    if (r > 0) last = now;
    if (r < 0) break;
    if (monitor.Received() + monitor.Malformed() > 0 &&
        std::chrono::duration<double>(now - last).count() > idle_s) {
      break;
    }
    if (std::chrono::duration<double>(now - start).count() > timeout_s) break;
    std::fflush(stdout);
  }
  int code = swf::cli::kExitOk;
  if (!map_out.empty()) {
    std::string text;
    const auto& m = monitor.LastMap();
    char line[160];
    for (int i = 0; i < m.num_landmarks; ++i) {
      std::snprintf(line, sizeof line, "%lld %.6f %.6f %.6f\n", static_cast<long long>(m.id[i]),
                    m.position_world_m[i][0], m.position_world_m[i][1], m.position_world_m[i][2]);
      text += line;
    }
    std::string error;
    if (!swf::cli::WriteFileAtomically(map_out, text, &error)) {
      std::fprintf(stderr, "swf-guidance: %s\n", error.c_str());
      code = swf::cli::kExitFailed;
    }
  }
  const auto& nav = monitor.LastNav();
  json hazard = Counts(monitor.Hazard(), true);
  hazard["last_frame"] =
      monitor.Hazard().received > 0 ? static_cast<long long>(monitor.LastHazard().frame_seq) : -1LL;
  hazard["last_site_valid"] = monitor.LastHazard().safe_site_valid != 0;
  const json summary = {{"nav", Counts(monitor.Nav(), true)},
                        {"landmarks", Counts(monitor.Landmarks(), true)},
                        {"health", Counts(monitor.Health(), false)},
                        {"hazard", hazard},
                        {"last_frame", nav.frame_seq},
                        {"last_position_m",
                         {Number(nav.position_world_m[0]), Number(nav.position_world_m[1]),
                          Number(nav.position_world_m[2])}},
                        {"last_map_landmarks", monitor.LastMap().num_landmarks},
                        {"overruns", monitor.LastHealth().overruns},
                        {"allocations_after_start", monitor.LastHealth().allocations_after_start},
                        {"run", swf::ground_cli::RunEcho(app, "swf-guidance", argc, argv)}};
  swf::ground_cli::PrintJson(summary, -1);
  return code;
}
