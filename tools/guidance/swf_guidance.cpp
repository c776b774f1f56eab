// swf-guidance: the guidance-side consumer of the flight process's LCM outputs. Prints every
// navigation state, landmark map, hazard map and health message (--quiet: only the summary), checks
// sequence numbers, counts malformed messages, and exits after --idle seconds without traffic (once
// something arrived) or --timeout seconds in all, printing a JSON summary on stdout.
//   swf-guidance [--url URL] [--prefix SWF_] [--idle S] [--timeout S] [--quiet]
//                [--map-out FILE]   (the last landmark map as "x y z" lines, for plotting)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "guidance_monitor.hpp"

int main(int argc, char** argv) {
  // The receive buffer holds a whole hazard map (~1.1 MB in fragments).
  std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  std::string prefix = "SWF_";
  std::string map_out;
  double idle_s = 2.0;
  double timeout_s = 120.0;
  bool quiet = false;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const bool v = a + 1 < argc;
    if (arg == "--url" && v)
      url = argv[++a];
    else if (arg == "--prefix" && v)
      prefix = argv[++a];
    else if (arg == "--idle" && v)
      idle_s = std::atof(argv[++a]);
    else if (arg == "--timeout" && v)
      timeout_s = std::atof(argv[++a]);
    else if (arg == "--map-out" && v)
      map_out = argv[++a];
    else if (arg == "--quiet")
      quiet = true;
    else {
      std::fprintf(stderr,
                   "usage: swf-guidance [--url URL] [--prefix P] [--idle S] [--timeout S] "
                   "[--quiet] [--map-out FILE]\n");
      return 2;
    }
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
  if (!map_out.empty()) {
    if (std::FILE* f = std::fopen(map_out.c_str(), "w")) {
      const auto& m = monitor.LastMap();
      for (int i = 0; i < m.num_landmarks; ++i) {
        std::fprintf(f, "%lld %.6f %.6f %.6f\n", static_cast<long long>(m.id[i]),
                     m.position_world_m[i][0], m.position_world_m[i][1], m.position_world_m[i][2]);
      }
      std::fclose(f);
    }
  }
  const auto& n = monitor.Nav();
  const auto& l = monitor.Landmarks();
  const auto& h = monitor.Health();
  const auto& z = monitor.Hazard();
  std::printf(
      "{\"nav\": {\"received\": %lld, \"lost\": %lld, \"out_of_order\": %lld, \"malformed\": "
      "%lld},\n \"landmarks\": {\"received\": %lld, \"lost\": %lld, \"out_of_order\": %lld, "
      "\"malformed\": %lld},\n \"health\": {\"received\": %lld, \"lost\": %lld, \"malformed\": "
      "%lld},\n \"hazard\": {\"received\": %lld, \"lost\": %lld, \"out_of_order\": %lld, "
      "\"malformed\": %lld, \"last_frame\": %lld, \"last_site_valid\": %s},\n"
      " \"last_frame\": %lld, \"last_position_m\": [%.3f, %.3f, %.3f], "
      "\"last_map_landmarks\": %d, \"overruns\": %lld, \"allocations_after_start\": %lld}\n",
      static_cast<long long>(n.received), static_cast<long long>(n.lost),
      static_cast<long long>(n.out_of_order), static_cast<long long>(n.malformed),
      static_cast<long long>(l.received), static_cast<long long>(l.lost),
      static_cast<long long>(l.out_of_order), static_cast<long long>(l.malformed),
      static_cast<long long>(h.received), static_cast<long long>(h.lost),
      static_cast<long long>(h.malformed), static_cast<long long>(z.received),
      static_cast<long long>(z.lost), static_cast<long long>(z.out_of_order),
      static_cast<long long>(z.malformed),
      static_cast<long long>(z.received > 0 ? monitor.LastHazard().frame_seq : -1),
      monitor.LastHazard().safe_site_valid ? "true" : "false",
      static_cast<long long>(monitor.LastNav().frame_seq), monitor.LastNav().position_world_m[0],
      monitor.LastNav().position_world_m[1], monitor.LastNav().position_world_m[2],
      monitor.LastMap().num_landmarks, static_cast<long long>(monitor.LastHealth().overruns),
      static_cast<long long>(monitor.LastHealth().allocations_after_start));
  return 0;
}
