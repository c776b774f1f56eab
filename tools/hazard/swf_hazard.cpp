// swf-hazard: evaluates hazard mapping on seeded simulated descents against the simulator's truth.
//
//   swf-hazard eval OUTDIR [--descents N] [--sweep-seeds S] [--shared DIR] [--width W]
//                          [--height H] [--downsample D]
//       altitude sweep (single-frame maps, fresh mapper per altitude) over the three terrain
//       presets: rock detection probability / false-alarm rate, slope error, elevation error vs
//       sigma against altitude; then N seeded fused descents per preset with the safe-site check.
//       Writes OUTDIR/hazard_eval.json, *.dat, hazard_*.png and hazard_map_*.png (swf::plot).
//   swf-hazard map OUT.png [--preset plains|craters|rocks] [--seed S] [--shared DIR]
//       one fused descent, the final hazard map as PNG.
// Every failure prints one line "swf-hazard: ..." naming the file (or option) and the cause, and
// exits 1; `eval` exits 1 too when a selected site lies on a true hazard (a failed result); a
// command line refused exits 2 (docs/cli.md). Output directories are created; every file is
// written under a temporary name and renamed when whole (SIGINT / SIGTERM remove it).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "run_filter.hpp"
#include "swf/evaluation/statistics.hpp"
#include "swf/ground_cli/ground_cli.hpp"
#include "swf/hazard_eval/hazard_eval.hpp"
#include "swf/plot/plot.hpp"
#include "swf/scene/runner.hpp"
#include "swf/sim/rng.hpp"
#include "swf/sim/trajectory.hpp"

namespace {

using swf::evaluation::Quantile;
using swf::hazard_eval::EvalOptions;
using swf::hazard_eval::HazardMapMetrics;
using swf::hazard_eval::World;

constexpr double kSweepAltitudes[] = {100.0, 80.0, 60.0, 50.0, 40.0, 30.0, 20.0, 15.0, 10.0};
constexpr double kDescentAltitudes[] = {80.0, 50.0, 30.0, 20.0, 14.0, 10.0};
const char* const kPresetNames[] = {"plains", "craters", "rocks"};

struct Acc {
  int rocks_in_view = 0, rocks_detected = 0, rocks_flagged = 0, false_cells = 0, free_cells = 0,
      frames = 0;
  double cell_m = 0.0, update_ms = 0.0;
  std::vector<double> slope_err, elev_err, elev_sigma;
  void Add(const HazardMapMetrics& m, double ms) {
    rocks_in_view += m.rocks_resolved;
    rocks_detected += m.rocks_detected;
    rocks_flagged += m.rocks_flagged;
    false_cells += m.false_rock_cells;
    free_cells += m.rock_free_cells;
    cell_m += m.cell_m;
    update_ms += ms;
    ++frames;
    slope_err.insert(slope_err.end(), m.slope_errors_deg.begin(), m.slope_errors_deg.end());
    elev_err.insert(elev_err.end(), m.elevation_errors_m.begin(), m.elevation_errors_m.end());
    elev_sigma.insert(elev_sigma.end(), m.elevation_sigmas_m.begin(), m.elevation_sigmas_m.end());
  }
  double Pd() const { return rocks_in_view > 0 ? double(rocks_detected) / rocks_in_view : NAN; }
  double Pf() const { return rocks_in_view > 0 ? double(rocks_flagged) / rocks_in_view : NAN; }
  double Far() const { return free_cells > 0 ? double(false_cells) / free_cells : NAN; }
  double WithinSigma(double k) const {
    if (elev_err.empty()) return NAN;
    int in = 0;
    for (std::size_t i = 0; i < elev_err.size(); ++i) in += elev_err[i] <= k * elev_sigma[i];
    return double(in) / elev_err.size();
  }
};

swf::estimator::Pose<double> CameraPose(const World& w, double x, double y, double altitude,
                                        double heading) {
  swf::estimator::Pose<double> p;
  p.R = swf::sim::NadirRotation(heading);
  p.t = {x, y, w.Terrain().HeightAt(x, y) + altitude};
  return p;
}

// Every failure: one line naming what failed (and the file), exit status 1.
int Fail(const std::string& why) {
  std::fprintf(stderr, "swf-hazard: %s\n", why.c_str());
  return 1;
}

// The hazard mapper refuses images smaller than this a side (HazardMapper::Configure), and the
// renderer would produce them: refused up front with the reason instead of as a configuration
// failure.
constexpr int kMinImageSide = 32;

// Configures the world and the mapper, or says which failed and why.
bool Prepare(World* world, swf::hazard::HazardMapper* mapper, swf::sim::TerrainPreset preset,
             std::uint64_t seed, const EvalOptions& eo, std::string* why) {
  if (eo.image_width < kMinImageSide || eo.image_height < kMinImageSide) {
    *why = "the image " + std::to_string(eo.image_width) + "x" + std::to_string(eo.image_height) +
           " px is smaller than the hazard mapper's minimum of " + std::to_string(kMinImageSide) +
           "x" + std::to_string(kMinImageSide) + " px (--width, --height)";
    return false;
  }
  if (world->Configure(preset, seed, eo, why) != swf::core::Status::kOk) return false;
  const swf::core::Status s = mapper->Configure(world->MapperOptions());
  if (s != swf::core::Status::kOk) {
    *why = std::string("the hazard mapper refuses its options (") + swf::core::ToString(s) +
           "; image " + std::to_string(eo.image_width) + "x" + std::to_string(eo.image_height) +
           " px, downsample " + std::to_string(eo.downsample) + ")";
    return false;
  }
  return true;
}

std::string StepFailure(int frame, double altitude_m, swf::core::Status s) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), "frame %d at %.1f m: the hazard update failed (%s)", frame,
                altitude_m, swf::core::ToString(s));
  return buf;
}

// The world's published map (World::Publish / Evaluate) drawn by swf::plot; false with the reason
// (naming the PNG) in `error`.
bool DrawPublished(const World& world, const EvalOptions& eo, const std::string& title,
                   const std::string& path, std::string* error) {
  if (!swf::cli::MakeParentDirectories(path, error)) return false;
  return swf::plot::DrawHazardMap(swf::hazard_eval::ViewOf(world.Published()),
                                  eo.footprint_radius_m, title, path, error);
}

// A picture kept for inspection while an evaluation goes on: a failure is said, not fatal.
void DrawForInspection(const World& world, const EvalOptions& eo, const std::string& title,
                       const std::string& path) {
  std::string error;
  if (!DrawPublished(world, eo, title, path, &error))
    std::fprintf(stderr, "swf-hazard: cannot draw %s\n", error.c_str());
}

std::string EvaluateFailure(swf::core::Status s) {
  return std::string("cannot publish the hazard map for evaluation (") + swf::core::ToString(s) +
         ")";
}

// The render noise of frame `frame` of the run seeded `seed`: every run draws its own frames.
std::uint64_t FrameSeed(std::uint64_t seed, int frame) { return seed * 1000 + frame; }

// One frame of a seeded run: mapped at `pose`, then the published map judged against the truth
// into `m` (the update's time in `ms`). False with the frame, its altitude and the failure in
// `why`.
bool MapAndJudge(World* world, swf::hazard::HazardMapper* mapper,
                 const swf::estimator::Pose<double>& pose, int frame, std::uint64_t seed,
                 double altitude_m, HazardMapMetrics* m, double* ms, std::string* why) {
  if (const swf::core::Status st = world->Step(pose, frame, FrameSeed(seed, frame), mapper, ms);
      st != swf::core::Status::kOk) {
    *why = StepFailure(frame, altitude_m, st);
    return false;
  }
  if (const swf::core::Status st = world->Evaluate(*mapper, m); st != swf::core::Status::kOk) {
    *why = EvaluateFailure(st);
    return false;
  }
  return true;
}

void Json(FILE* f, double v) {
  if (std::isfinite(v)) {
    std::fprintf(f, "%.6g", v);
  } else {
    std::fprintf(f, "null");
  }
}

int Eval(const std::string& out, const EvalOptions& eo, int descents, int sweep_seeds,
         int only_preset) {
  std::string error;
  swf::cli::OutputFile json_file;
  if (!json_file.Open(out + "/hazard_eval.json", &error)) return Fail(error);
  FILE* json = json_file.Stream();
  constexpr int kNumAlt = sizeof(kSweepAltitudes) / sizeof(kSweepAltitudes[0]);
  std::vector<std::vector<Acc>> sweep(3, std::vector<Acc>(kNumAlt));
  std::vector<Acc> all_alt(kNumAlt);
  auto mapper = std::make_unique<swf::hazard::HazardMapper>();
  for (int p = 0; p < 3; ++p) {
    for (int s = 0; s < sweep_seeds; ++s) {
      World world;
      const auto seed = static_cast<std::uint64_t>(100 + s);
      std::string why;
      if (!Prepare(&world, mapper.get(), static_cast<swf::sim::TerrainPreset>(p), seed, eo, &why))
        return Fail(why);
      swf::sim::Rng rng(seed * 7919);
      for (int a = 0; a < kNumAlt; ++a) {
        mapper->Reset();
        const double x = rng.Uniform(-20.0, 20.0);
        const double y = rng.Uniform(-20.0, 20.0);
        const auto pose = CameraPose(world, x, y, kSweepAltitudes[a], rng.Uniform(0.0, 6.283));
        double ms = 0.0;
        HazardMapMetrics m;
        if (!MapAndJudge(&world, mapper.get(), pose, a, seed, kSweepAltitudes[a], &m, &ms, &why))
          return Fail(std::string(kPresetNames[p]) + " seed " + std::to_string(seed) + ": " + why);
        sweep[p][a].Add(m, ms);
        all_alt[a].Add(m, ms);
        if (p == 2 && s == 0 && (a == 5 || a == 7)) {
          const std::string altitude = std::to_string(int(kSweepAltitudes[a]));
          DrawForInspection(world, eo, "Hazard map, rocks terrain, static at " + altitude + " m",
                            out + "/hazard_map_rocks_" + altitude + "m.png");
        }
      }
      std::fprintf(stderr, "sweep %s seed %d done\n", kPresetNames[p], s);
    }
  }
  // Descents.
  struct DescentResult {
    int preset;
    int seed;
    bool valid;
    bool on_hazard;
    double clearance;
    int stable;
  };
  std::vector<DescentResult> results;
  std::vector<Acc> descent_acc(3);
  for (int p = 0; p < 3; ++p) {
    if (only_preset >= 0 && p != only_preset) continue;
    for (int s = 0; s < descents; ++s) {
      World world;
      const auto seed = static_cast<std::uint64_t>(1000 + s);
      std::string why;
      if (!Prepare(&world, mapper.get(), static_cast<swf::sim::TerrainPreset>(p), seed, eo, &why))
        return Fail(why);
      swf::sim::Rng rng(seed * 104729);
      const double x0 = rng.Uniform(-20.0, 20.0);
      const double y0 = rng.Uniform(-20.0, 20.0);
      const double heading = rng.Uniform(0.0, 6.283);
      int f = 0;
      HazardMapMetrics m;
      double ms = 0.0;
      for (double alt : kDescentAltitudes) {
        const auto pose =
            CameraPose(world, x0 + 0.2 * rng.Gaussian(), y0 + 0.2 * rng.Gaussian(), alt, heading);
        if (!MapAndJudge(&world, mapper.get(), pose, f, seed, alt, &m, &ms, &why)) {
          return Fail(std::string(kPresetNames[p]) + " descent seed " + std::to_string(seed) +
                      ": " + why);
        }
        ++f;
      }
      descent_acc[p].Add(m, ms);
      results.push_back({p, s, m.site_valid, m.site_on_hazard, m.site_clearance_m,
                         mapper->Site().stable_updates});
      if (s == 0) {
        DrawForInspection(
            world, eo, std::string("Hazard map after a descent, ") + kPresetNames[p] + " terrain",
            out + "/hazard_map_descent_" + kPresetNames[p] + ".png");
      }
      if (m.site_valid && m.site_on_hazard) {  // every failure kept for inspection
        DrawForInspection(
            world, eo,
            std::string("Safe site on a true hazard: ") + kPresetNames[p] + " terrain, seed " +
                std::to_string(s),
            out + "/hazard_map_failed_" + kPresetNames[p] + "_" + std::to_string(s) + ".png");
      }
    }
    std::fprintf(stderr, "descents %s done\n", kPresetNames[p]);
  }
  // JSON.
  std::fprintf(json, "{\n  \"image\": [%d, %d], \"downsample\": %d, \"footprint_radius_m\": %g,\n",
               eo.image_width, eo.image_height, eo.downsample, eo.footprint_radius_m);
  std::fprintf(json, "  \"max_rock_height_m\": %g, \"max_slope_deg\": %g,\n", eo.max_rock_height_m,
               eo.max_slope_deg);
  std::fprintf(json, "  \"sweep_seeds_per_preset\": %d,\n  \"sweep\": [\n", sweep_seeds);
  swf::cli::OutputFile dat_file;
  FILE* dat = dat_file.Open(out + "/hazard_sweep.dat", &error) ? dat_file.Stream() : nullptr;
  if (dat == nullptr) {
    return Fail(error);
  }
  std::fprintf(dat,
               "# altitude pd_all far_all pd_plains pd_craters pd_rocks slope_med slope_p90 "
               "within1 within2 sigma_med cell_m dz_formula pflag_all\n");
  const double fx = eo.image_width / 2.0 / std::tan(12.5 * M_PI / 180.0) / eo.downsample;
  for (int a = 0; a < kNumAlt; ++a) {
    const Acc& t = all_alt[a];
    const double z = kSweepAltitudes[a];
    const double dz = z * z * 0.25 / (fx * 1.0);
    std::fprintf(json, "    {\"altitude_m\": %g, \"cell_m\": ", z);
    Json(json, t.cell_m / std::max(1, t.frames));
    std::fprintf(json, ", \"rocks_in_view\": %d, \"detection_probability\": ", t.rocks_in_view);
    Json(json, t.Pd());
    std::fprintf(json, ", \"flagged_probability\": ");
    Json(json, t.Pf());
    std::fprintf(json, ", \"false_alarm_rate\": ");
    Json(json, t.Far());
    std::fprintf(json, ", \"detection_probability_by_preset\": [");
    for (int p = 0; p < 3; ++p) {
      Json(json, sweep[p][a].Pd());
      std::fprintf(json, p < 2 ? ", " : "]");
    }
    std::fprintf(json, ", \"slope_error_median_deg\": ");
    Json(json, Quantile(t.slope_err, 0.5));
    std::fprintf(json, ", \"slope_error_p90_deg\": ");
    Json(json, Quantile(t.slope_err, 0.9));
    std::fprintf(json, ", \"elevation_within_1sigma\": ");
    Json(json, t.WithinSigma(1.0));
    std::fprintf(json, ", \"elevation_within_2sigma\": ");
    Json(json, t.WithinSigma(2.0));
    std::fprintf(json, ", \"elevation_sigma_median_m\": ");
    Json(json, Quantile(t.elev_sigma, 0.5));
    std::fprintf(json, ", \"elevation_error_median_m\": ");
    Json(json, Quantile(t.elev_err, 0.5));
    std::fprintf(json, ", \"range_resolution_formula_m\": ");
    Json(json, dz);
    std::fprintf(json, ", \"update_ms_mean\": ");
    Json(json, t.update_ms / std::max(1, t.frames));
    std::fprintf(json, "}%s\n", a + 1 < kNumAlt ? "," : "");
    std::fprintf(dat, "%g %g %g %g %g %g %g %g %g %g %g %g %g %g\n", z, t.Pd(), t.Far(),
                 sweep[0][a].Pd(), sweep[1][a].Pd(), sweep[2][a].Pd(), Quantile(t.slope_err, 0.5),
                 Quantile(t.slope_err, 0.9), t.WithinSigma(1.0), t.WithinSigma(2.0),
                 Quantile(t.elev_sigma, 0.5), t.cell_m / std::max(1, t.frames), dz, t.Pf());
  }
  if (!dat_file.Commit(&error)) return Fail(error);
  int valid = 0;
  int on_hazard = 0;
  double min_clear = 1e9;
  std::vector<double> clear;
  for (const DescentResult& r : results) {
    valid += r.valid;
    on_hazard += r.valid && r.on_hazard;
    if (r.valid) {
      min_clear = std::min(min_clear, r.clearance);
      clear.push_back(r.clearance);
    }
  }
  std::fprintf(json,
               "  ],\n  \"descents\": {\"count\": %zu, \"per_preset\": %d, "
               "\"altitudes_m\": [80, 50, 30, 20, 14, 10],\n",
               results.size(), descents);
  std::fprintf(json,
               "    \"site_found\": %d, \"site_on_true_hazard\": %d, "
               "\"site_clearance_min_m\": ",
               valid, on_hazard);
  Json(json, valid > 0 ? min_clear : NAN);
  std::fprintf(json, ", \"site_clearance_median_m\": ");
  Json(json, Quantile(clear, 0.5));
  std::fprintf(json, ",\n    \"final_map\": [");
  for (int p = 0; p < 3; ++p) {
    const Acc& t = descent_acc[p];
    std::fprintf(json, "{\"preset\": \"%s\", \"detection_probability\": ", kPresetNames[p]);
    Json(json, t.Pd());
    std::fprintf(json, ", \"flagged_probability\": ");
    Json(json, t.Pf());
    std::fprintf(json, ", \"false_alarm_rate\": ");
    Json(json, t.Far());
    std::fprintf(json, ", \"elevation_within_1sigma\": ");
    Json(json, t.WithinSigma(1.0));
    std::fprintf(json, ", \"slope_error_median_deg\": ");
    Json(json, Quantile(t.slope_err, 0.5));
    std::fprintf(json, "}%s", p < 2 ? ", " : "]");
  }
  std::fprintf(json, ",\n    \"runs\": [");
  for (std::size_t i = 0; i < results.size(); ++i) {
    const DescentResult& r = results[i];
    char clearance[32] = "null";  // no site, no clearance
    if (r.valid) std::snprintf(clearance, sizeof clearance, "%.3f", r.clearance);
    std::fprintf(json,
                 "%s{\"preset\": \"%s\", \"seed\": %d, \"site\": %s, \"on_hazard\": %s, "
                 "\"clearance_m\": %s, \"stable_updates\": %d}",
                 i == 0 ? "\n      " : ",\n      ", kPresetNames[r.preset], r.seed,
                 r.valid ? "true" : "false", r.on_hazard ? "true" : "false", clearance, r.stable);
  }
  std::fprintf(json, "]\n  }\n}\n");
  if (!json_file.Commit(&error)) return Fail(error);
  // Plots, by altitude of the static sweep.
  const auto series = [&](const std::string& title, auto&& value) {
    swf::plot::Series line{title, {}, {}};
    for (int a = 0; a < kNumAlt; ++a) {
      line.x.push_back(kSweepAltitudes[a]);
      line.y.push_back(value(a));
    }
    return line;
  };
  const auto pd_of = [&](int p) {
    return series(std::string("P_d ") + kPresetNames[p],
                  [&, p](int a) { return sweep[p][a].Pd(); });
  };
  char rocks[96];
  std::snprintf(rocks, sizeof rocks,
                "Rocks >= %.2f m: detection probability and false-alarm rate by altitude",
                eo.max_rock_height_m);
  const swf::plot::LineChart charts[] = {
      {rocks,
       "camera altitude (m)",
       "probability or rate",
       false,
       {series("P_d (all terrains)", [&](int a) { return all_alt[a].Pd(); }),
        series("P(flagged: rock or uncertain)", [&](int a) { return all_alt[a].Pf(); }), pd_of(0),
        pd_of(1), pd_of(2),
        series("false-alarm rate x 100", [&](int a) { return 100.0 * all_alt[a].Far(); })}},
      {"Elevation error against the mapper's own sigma, by altitude",
       "camera altitude (m)",
       "fraction of cells, or metres",
       false,
       {series("fraction of cells within 1 sigma (expected 0.683)",
               [&](int a) { return all_alt[a].WithinSigma(1.0); }),
        series("fraction within 2 sigma (expected 0.954)",
               [&](int a) { return all_alt[a].WithinSigma(2.0); }),
        series("median sigma (m)", [&](int a) { return Quantile(all_alt[a].elev_sigma, 0.5); }),
        series("dZ = Z^2 0.25 px / (f B) (m)",
               [&](int a) { return kSweepAltitudes[a] * kSweepAltitudes[a] * 0.25 / fx; })}},
      {"Slope error of the footprint plane, by altitude",
       "camera altitude (m)",
       "slope error (deg)",
       false,
       {series("median", [&](int a) { return Quantile(all_alt[a].slope_err, 0.5); }),
        series("90th percentile", [&](int a) { return Quantile(all_alt[a].slope_err, 0.9); })}}};
  const char* const chart_files[] = {"hazard_detection.png", "hazard_elevation.png",
                                     "hazard_slope.png"};
  bool drawn = true;
  for (int c = 0; c < 3; ++c) {
    std::string error;
    if (!swf::plot::DrawLineChart(charts[c], out + "/" + chart_files[c], &error)) {
      std::fprintf(stderr, "swf-hazard: cannot draw %s\n", error.c_str());
      drawn = false;
    }
  }
  std::printf("%s/hazard_eval.json: %d descents, site found %d, on true hazard %d\n", out.c_str(),
              static_cast<int>(results.size()), valid, on_hazard);
  if (!drawn) return swf::cli::kExitFailed;
  return on_hazard == 0 ? swf::cli::kExitOk : swf::cli::kExitFailed;
}

int Map(const std::string& path, const EvalOptions& eo, swf::sim::TerrainPreset preset,
        std::uint64_t seed) {
  World world;
  auto mapper = std::make_unique<swf::hazard::HazardMapper>();
  std::string why;
  if (!Prepare(&world, mapper.get(), preset, seed, eo, &why)) return Fail(path + ": " + why);
  int f = 0;
  for (double alt : kDescentAltitudes) {
    if (const swf::core::Status st = world.Step(CameraPose(world, 0.0, 0.0, alt, 0.0), f,
                                                FrameSeed(seed, f), mapper.get(), nullptr);
        st != swf::core::Status::kOk) {
      return Fail(path + ": " + StepFailure(f, alt, st));
    }
    ++f;
  }
  if (const swf::core::Status st = world.Publish(*mapper); st != swf::core::Status::kOk)
    return Fail(path + ": " + EvaluateFailure(st));
  std::string error;
  if (!DrawPublished(world, eo,
                     "Hazard map after a descent, " +
                         std::string(kPresetNames[static_cast<int>(preset)]) + " terrain, seed " +
                         std::to_string(seed),
                     path, &error))
    return Fail(error);
  return 0;
}

// Disparity error of the mapper's last SGM against the rendered exact depth (working pixels).
struct SgmError {
  int valid = 0;
  double median_abs = NAN, robust_sigma = NAN, rms_clipped = NAN, frac_over_1px = NAN;
  double corr[4] = {NAN, NAN, NAN, NAN};  // error autocorrelation at lags 1, 2, 4, 8 px (|e|<1)
};
SgmError MeasureSgm(const World& w, const swf::hazard::HazardMapper& m) {
  SgmError r;
  const swf::sim::StereoImages& im = w.Images();
  const swf::hazard::HazardMapperOptions& o = m.Options();
  const int ds = o.downsample;
  const double fb = o.camera.fx / ds * o.camera.baseline_m;
  std::vector<double> e;
  const swf::hazard::SgmMatcher& s = m.Stereo();
  std::vector<float> img(static_cast<std::size_t>(s.Width()) * s.Height(), NAN);
  for (int v = 0; v < s.Height(); ++v) {
    for (int u = 0; u < s.Width(); ++u) {
      const float d = s.DisparityAt(u, v);
      if (!(d > 0.5f) || s.ConfidenceAt(u, v) < o.min_confidence) continue;
      const int fu = std::min(u * ds, im.width - 1);
      const int fv = std::min(v * ds, im.height - 1);
      const float z = im.depth_m[static_cast<std::size_t>(fv) * im.width + fu];
      if (!std::isfinite(z)) continue;
      e.push_back(d - fb / z);
      if (std::fabs(e.back()) < 1.0) img[static_cast<std::size_t>(v) * s.Width() + u] = e.back();
    }
  }
  const int lags[4] = {1, 2, 4, 8};
  for (int l = 0; l < 4; ++l) {
    double sab = 0, saa = 0, sbb = 0, sa = 0, sb = 0;
    int cnt = 0;
    for (int v = 0; v < s.Height(); ++v) {
      for (int u = 0; u + lags[l] < s.Width(); ++u) {
        const float a = img[static_cast<std::size_t>(v) * s.Width() + u];
        const float b = img[static_cast<std::size_t>(v) * s.Width() + u + lags[l]];
        if (std::isnan(a) || std::isnan(b)) continue;
        sab += a * b;
        saa += a * a;
        sbb += b * b;
        sa += a;
        sb += b;
        ++cnt;
      }
    }
    if (cnt > 10) {
      const double ma = sa / cnt, mb = sb / cnt;
      r.corr[l] = (sab / cnt - ma * mb) / std::sqrt((saa / cnt - ma * ma) * (sbb / cnt - mb * mb));
    }
  }
  r.valid = static_cast<int>(e.size());
  if (e.empty()) return r;
  std::vector<double> a(e.size());
  int over = 0;
  double ss = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    a[i] = std::fabs(e[i]);
    over += a[i] > 1.0;
    if (a[i] <= 1.0) {
      ss += e[i] * e[i];
      ++n;
    }
  }
  r.median_abs = Quantile(a, 0.5);
  r.robust_sigma = 1.4826 * r.median_abs;
  r.rms_clipped = n > 0 ? std::sqrt(ss / n) : NAN;
  r.frac_over_1px = double(over) / e.size();
  return r;
}

// The flight demo's geometry without the flight process: a vertical descent over one terrain
// (preset, seed, size as in swf-fsw's sim source) from 100 to 10 m, one hazard update every
// `step` metres, per-update measurements printed as a table (and OUTDIR/flight.dat).
//
// With `swf`: the pose error and covariance given to the mapper come from a SlidingWindowFilter
// run on the measurement-level generator (swf/scene/synthetic_scene.hpp: 0.5 px stereo
// features, 10 cm / 2 mrad motion inputs, window 5) along the same altitudes, one frame per
// hazard update: error = truth.LocalDifference(estimate), covariance = its newest-pose marginal.
struct SwfPoses {
  std::vector<Eigen::Matrix<double, 6, 1>> error;
  std::vector<Eigen::Matrix<double, 6, 6>> covariance;
  std::vector<double> nees;
};
// swf-eval's filter (window up to 40, 300 landmarks active, 200 per frame), compiled there.
using SwfFilter = swf::eval::Filter;

bool RunSwfAlongDescent(int frames, double step, std::uint64_t seed, SwfPoses* out) {
  swf::scene::SceneOptions so;
  so.motion = swf::scene::SceneOptions::Motion::kDescent;
  so.frames = frames;
  so.start_altitude_m = 100.0;
  so.step_m = step;
  so.num_landmarks = 600;
  so.landmark_radius_m = 20.0;
  so.max_obs_per_frame = 150;
  so.jitter_rad = 0.1 * M_PI / 180.0;
  so.seed = seed;
  const swf::scene::SyntheticScene scene(so);
  out->error.assign(frames, Eigen::Matrix<double, 6, 1>::Zero());
  out->covariance.assign(frames, Eigen::Matrix<double, 6, 6>::Zero());
  out->nees.assign(frames, NAN);
  bool ok = true;
  auto hook = [&](SwfFilter* f, std::size_t j) {
    if (f->ComputeCovariances() != swf::core::Status::kOk) {
      ok = false;
      return;
    }
    const swf::estimator::Pose<double>& truth = scene.frames()[j].truth;
    out->error[j] = truth.LocalDifference(f->NewestPose());
    out->covariance[j] = f->NewestPoseCovariance();
    out->nees[j] = out->error[j].dot(out->covariance[j].ldlt().solve(out->error[j]));
  };
  auto swf = std::make_unique<SwfFilter>();
  swf::estimator::SwfOptions options =
      swf::scene::FilterOptions(swf::estimator::SwfMode::kSlidingWindow);
  options.window_size = 5;
  const swf::scene::Trace trace = swf::scene::RunScene(
      swf.get(), scene, options,
      swf::scene::MotionInput(swf::scene::MotionInput::kSigmaM, swf::scene::MotionInput::kSigmaRad,
                              seed * 31 + 7),
      hook);
  return ok && trace.configured == swf::core::Status::kOk;
}

// Calibration of the published relief sigma on rock-free ground: the relief error of a cell is
// its elevation error less the plane the mapper fits over the same window (the plane is linear in
// the heights, so this is relief_map - relief_truth on the map's own known cells). Counted where
// the rock criterion resolves the threshold (relief sigma <= sigma_max), the cells it decides.
// Also the calibration of the "rock possible" test's box sigma (hazard_mapper.hpp, RockCriterion,
// "Possible") where it applies (relief sigma > sigma_max): the mean relief error over each
// rock-free, wholly known footprint box, over RockCriterion::FootprintSigma of the box's relief
// sigmas (each taken as stereo sigma: the plane's part, ~1/60 of it, enters at rho instead of 1).
// Errors over their stated sigma: the share within 1 sigma, the share above `tail` sigmas and
// the robust scale (1.4826 x the median |z|: 1 for a calibrated sigma).
struct NormalizedErrors {
  double within1 = NAN, over_tail = NAN, robust_scale = NAN;
};

NormalizedErrors SummarizeNormalizedErrors(const std::vector<double>& z, double tail) {
  NormalizedErrors e;
  if (z.empty()) return e;
  int in1 = 0, over = 0;
  std::vector<double> a;
  for (double v : z) {
    in1 += std::fabs(v) <= 1.0;
    over += v > tail;
    a.push_back(std::fabs(v));
  }
  e.within1 = double(in1) / z.size();
  e.over_tail = double(over) / z.size();
  e.robust_scale = 1.4826 * Quantile(a, 0.5);
  return e;
}

struct ReliefCalibration {
  int cells = 0;
  NormalizedErrors cell;  // tail 3.09 sigma
  int boxes = 0;
  NormalizedErrors box;     // tail 2 sigma
  double cell_over2 = NAN;  // the same boxes' centre cells alone, relief error over relief sigma
};

// relief_error (optional): every rock-free cell's relief error over its relief sigma (NaN
// elsewhere).
ReliefCalibration CalibrateRelief(const World& world, const swf::hazard::HazardMapper& mapper,
                                  std::vector<float>* relief_error = nullptr) {
  ReliefCalibration r;
  swf::hazard_eval::MetricOptions mo;
  mo.cell_errors = false;
  const swf_msgs::hazard_truth_t truth =
      swf::hazard_eval::HazardTruthOf(swf::hazard_eval::ViewOf(world.Published()), world.Terrain(),
                                      world.Terrain().Rocks(), world.Truth(), mo);
  const int n = mapper.GridCells();
  const double cell = mapper.CellM();
  const swf::hazard::RockCriterion criterion(swf::hazard::RockCriterionOf(mapper.Options()), cell);
  const int rr =
      std::max(1, static_cast<int>(std::lround(mapper.Options().rock_window_radius_m / cell)));
  std::vector<double> err(static_cast<std::size_t>(n) * n, NAN);
  for (std::size_t c = 0; c < err.size(); ++c) {
    if (!std::isnan(mapper.Elevation()[c]) && std::isfinite(truth.elevation_m[c])) {
      err[c] = mapper.Elevation()[c] - truth.elevation_m[c];
    }
  }
  // Summed-area tables of 1, x, y, e, xx, xy, yy, xe, ye over the known cells.
  constexpr int kCh = 9;
  const int n1 = n + 1;
  std::vector<double> sat(static_cast<std::size_t>(n1) * n1 * kCh, 0.0);
  for (int j = 0; j < n; ++j) {
    double row[kCh] = {};
    for (int i = 0; i < n; ++i) {
      const double e = err[static_cast<std::size_t>(j) * n + i];
      if (!std::isnan(e)) {
        const double v[kCh] = {1.0,           double(i),     double(j), e,    double(i) * i,
                               double(i) * j, double(j) * j, i * e,     j * e};
        for (int k = 0; k < kCh; ++k) row[k] += v[k];
      }
      for (int k = 0; k < kCh; ++k) {
        sat[(static_cast<std::size_t>(j + 1) * n1 + i + 1) * kCh + k] =
            sat[(static_cast<std::size_t>(j) * n1 + i + 1) * kCh + k] + row[k];
      }
    }
  }
  std::vector<double> z;
  std::vector<double> rel(err.size(), NAN);  // relief error per cell (any relief sigma)
  std::vector<double> rel_z(err.size(), NAN);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      const double sigma = mapper.ReliefSigma()[c];
      if (std::isnan(err[c]) || std::isnan(sigma) || !truth.rock_free[c]) continue;
      const bool decided = sigma <= criterion.ResolvedSigma();
      const int i0 = std::max(0, i - rr), j0 = std::max(0, j - rr);
      const int i1 = std::min(n, i + rr + 1), j1 = std::min(n, j + rr + 1);
      double s[kCh];
      for (int k = 0; k < kCh; ++k) {
        const auto at = [&](int a, int b) {
          return sat[(static_cast<std::size_t>(b) * n1 + a) * kCh + k];
        };
        s[k] = at(i1, j1) - at(i1, j0) - at(i0, j1) + at(i0, j0);
      }
      const double m = s[0];
      const double mx = s[1] / m, my = s[2] / m, me = s[3] / m;
      const double cxx = s[4] / m - mx * mx, cxy = s[5] / m - mx * my, cyy = s[6] / m - my * my;
      const double cxe = s[7] / m - mx * me, cye = s[8] / m - my * me;
      const double det = cxx * cyy - cxy * cxy;
      if (!(det > 1e-6)) continue;
      const double b = (cyy * cxe - cxy * cye) / det;
      const double cc = (cxx * cye - cxy * cxe) / det;
      rel[c] = err[c] - (me + b * (i - mx) + cc * (j - my));
      rel_z[c] = rel[c] / sigma;
      if (decided) z.push_back(rel_z[c]);
    }
  }
  if (relief_error != nullptr) relief_error->assign(rel_z.begin(), rel_z.end());
  // The footprint boxes centred on undecided cells, every box cell with a relief error.
  const int half = (criterion.FootprintCells() - 1) / 2;
  std::vector<double> box_z;
  int cell_over2 = 0;
  for (int j = half; j < n - half; ++j) {
    for (int i = half; i < n - half; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * n + i;
      if (std::isnan(rel[c]) || !(mapper.ReliefSigma()[c] > criterion.ResolvedSigma())) continue;
      double sum = 0.0, sum_s = 0.0, sum_s2 = 0.0;
      bool whole = true;
      for (int b = j - half; b <= j + half && whole; ++b) {
        for (int a = i - half; a <= i + half; ++a) {
          const std::size_t q = static_cast<std::size_t>(b) * n + a;
          if (std::isnan(rel[q])) {
            whole = false;
            break;
          }
          const double sq = mapper.ReliefSigma()[q];
          sum += rel[q];
          sum_s += sq;
          sum_s2 += sq * sq;
        }
      }
      if (!whole) continue;
      const double cells = double(criterion.FootprintCells()) * criterion.FootprintCells();
      box_z.push_back(sum / cells / criterion.FootprintSigma(sum_s, sum_s2, 0.0));
      cell_over2 += rel_z[c] > 2.0;
    }
  }
  r.boxes = static_cast<int>(box_z.size());
  r.box = SummarizeNormalizedErrors(box_z, 2.0);
  if (!box_z.empty()) r.cell_over2 = double(cell_over2) / box_z.size();
  r.cells = static_cast<int>(z.size());
  r.cell = SummarizeNormalizedErrors(z, 3.09);
  return r;
}

// One single-frame map's relief errors (CalibrateRelief), for the correlation between frames.
struct FrameErrors {
  double altitude_m = 0.0;
  double cell_m = 0.0;
  double corner_x = 0.0, corner_y = 0.0;
  std::vector<float> relief_z;
};

// The correlation of two frames' relief errors over the cells both hold (same cell size and
// lattice), against the ratio of their altitudes (nearer / farther; 1 = the same viewpoint): how
// much of their stereo error frames share (hazard_mapper.hpp, frame_error_correlation).
void PrintFrameCorrelation(const std::vector<FrameErrors>& frames) {
  std::printf("# frame correlation: alt_a alt_b ratio cells correlation\n");
  for (std::size_t a = 0; a < frames.size(); ++a) {
    for (std::size_t b = a + 1; b < frames.size(); ++b) {
      const FrameErrors& fa = frames[a];
      const FrameErrors& fb = frames[b];
      if (fa.cell_m != fb.cell_m || fa.relief_z.size() != fb.relief_z.size()) continue;
      // The same ground: b's cell holding the centre of a's (the grids follow each frame's
      // nadir, placed with that frame's pose).
      const int side = static_cast<int>(std::lround(std::sqrt(double(fa.relief_z.size()))));
      const int di = static_cast<int>(std::floor((fa.corner_x - fb.corner_x) / fa.cell_m + 0.5));
      const int dj = static_cast<int>(std::floor((fa.corner_y - fb.corner_y) / fa.cell_m + 0.5));
      double n = 0, sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
      for (int j = 0; j < side; ++j) {
        const int jb = j + dj;
        if (jb < 0 || jb >= side) continue;
        for (int i = 0; i < side; ++i) {
          const int ib = i + di;
          if (ib < 0 || ib >= side) continue;
          const double x = fa.relief_z[static_cast<std::size_t>(j) * side + i];
          const double y = fb.relief_z[static_cast<std::size_t>(jb) * side + ib];
          if (std::isnan(x) || std::isnan(y)) continue;
          n += 1;
          sa += x;
          sb += y;
          saa += x * x;
          sbb += y * y;
          sab += x * y;
        }
      }
      if (n < 100) continue;
      const double cov = sab / n - sa / n * sb / n;
      const double va = saa / n - sa / n * sa / n, vb = sbb / n - sb / n * sb / n;
      if (!(va > 0.0 && vb > 0.0)) continue;
      std::printf("frame correlation %.1f %.1f %.3f %.0f %.3f\n", fa.altitude_m, fb.altitude_m,
                  std::min(fa.altitude_m, fb.altitude_m) / std::max(fa.altitude_m, fb.altitude_m),
                  n, cov / std::sqrt(va * vb));
    }
  }
}

int Flight(const std::string& out, const EvalOptions& eo, swf::sim::TerrainPreset preset,
           std::uint64_t seed, double x0, double y0, double step, bool swf, bool relief_calibration,
           bool frame_correlation) {
  SwfPoses poses;
  const int frames = static_cast<int>(std::floor(90.0 / step + 1e-9)) + 1;
  if (swf && !RunSwfAlongDescent(frames, step, seed, &poses)) {
    return Fail("the SWF along the descent could not compute its covariances");
  }
  World world;
  auto mapper = std::make_unique<swf::hazard::HazardMapper>();
  auto single = std::make_unique<swf::hazard::HazardMapper>();
  std::string why;
  if (!Prepare(&world, mapper.get(), preset, seed, eo, &why)) return Fail(why);
  if (single->Configure(mapper->Options()) != swf::core::Status::kOk) return Fail("single mapper");
  swf::cli::OutputFile dat_file;
  if (!dat_file.Open(out + "/flight.dat", &why)) return Fail(why);
  FILE* dat = dat_file.Stream();
  const char* head =
      "# alt cell known safe unc slope rock in1s in2s sig_med err_med slope_err_med "
      "sgm_valid sgm_med_abs sgm_robust_sigma sgm_rms_clip sgm_over1 site clear rocks_res "
      "rocks_det far c1 c2 c4 c8 dscale ncal outliers replaced\n";
  std::fputs(head, dat);
  std::fputs(head, stdout);
  std::vector<FrameErrors> frame_errors;
  int f = 0;
  for (int fi = 0; fi < frames; ++fi) {
    const double alt = 100.0 - step * fi;
    // The demo's trajectory: heading 0, nadir, absolute height 100 m at the start.
    swf::estimator::Pose<double> pose;
    pose.R = swf::sim::NadirRotation(0.0);
    pose.t = {x0, y0, alt};
    double ms = 0.0;
    if (const swf::core::Status st =
            world.Step(pose, f, FrameSeed(seed, f), mapper.get(), &ms,
                       swf ? &poses.error[f] : nullptr, swf ? &poses.covariance[f] : nullptr);
        st != swf::core::Status::kOk) {
      return Fail(StepFailure(f, alt, st));
    }
    // The relief sigma's calibration, fused and single-frame (a fresh mapper on the same pair).
    if (relief_calibration) {
      const ReliefCalibration fused = [&] {
        (void)world.Publish(*mapper);
        return CalibrateRelief(world, *mapper);
      }();
      single->Reset();
      double ms1 = 0.0;
      (void)world.Step(pose, f, FrameSeed(seed, f), single.get(), &ms1,
                       swf ? &poses.error[f] : nullptr, swf ? &poses.covariance[f] : nullptr);
      (void)world.Publish(*single);
      const ReliefCalibration one = CalibrateRelief(world, *single);
      std::printf(
          "# relief calibration at %.1f m, cell %.3f m: fused %d cells, %.3f within 1 sigma, "
          "%.4f above 3.09 sigma, robust scale %.2f | single frame %d cells, %.3f, %.4f, %.2f\n",
          alt, mapper->CellM(), fused.cells, fused.cell.within1, fused.cell.over_tail,
          fused.cell.robust_scale, one.cells, one.cell.within1, one.cell.over_tail,
          one.cell.robust_scale);
      std::printf(
          "# footprint calibration at %.1f m, cell %.3f m, box %d cells: fused %d boxes, %.3f "
          "within 1 sigma, %.4f above 2 sigma (their centre cells alone: %.4f), robust scale "
          "%.2f | single frame %d, %.3f, %.4f (%.4f), %.2f\n",
          alt, mapper->CellM(),
          swf::hazard::RockCriterion(swf::hazard::RockCriterionOf(mapper->Options()),
                                     mapper->CellM())
              .FootprintCells(),
          fused.boxes, fused.box.within1, fused.box.over_tail, fused.cell_over2,
          fused.box.robust_scale, one.boxes, one.box.within1, one.box.over_tail, one.cell_over2,
          one.box.robust_scale);
    }
    if (frame_correlation) {
      single->Reset();
      double ms1 = 0.0;
      (void)world.Step(pose, f, FrameSeed(seed, f), single.get(), &ms1,
                       swf ? &poses.error[f] : nullptr, swf ? &poses.covariance[f] : nullptr);
      (void)world.Publish(*single);
      FrameErrors e{alt, single->CellM(), single->CornerX(), single->CornerY(), {}};
      CalibrateRelief(world, *single, &e.relief_z);
      frame_errors.push_back(std::move(e));
    }
    if (swf) {
      std::printf(
          "# swf frame %d: position error %.3f m (sigma %.3f), attitude error %.4f deg "
          "(sigma %.4f), NEES %.2f\n",
          f, poses.error[f].head<3>().norm(),
          std::sqrt(poses.covariance[f].topLeftCorner<3, 3>().trace()),
          poses.error[f].tail<3>().norm() * 180.0 / M_PI,
          std::sqrt(poses.covariance[f].bottomRightCorner<3, 3>().trace()) * 180.0 / M_PI,
          poses.nees[f]);
    }
    ++f;
    const double agl = alt - world.Terrain().HeightAt(x0, y0);
    HazardMapMetrics m;
    if (const swf::core::Status st2 = world.Evaluate(*mapper, &m); st2 != swf::core::Status::kOk) {
      return Fail(EvaluateFailure(st2));
    }
    Acc acc;
    acc.Add(m, ms);
    const SgmError se = MeasureSgm(world, *mapper);
    const swf::hazard::HazardStats& st = mapper->Stats();
    const double k = std::max(1, st.known_cells);
    const std::string line = [&] {
      char b[512];
      std::snprintf(b, sizeof b,
                    "%.1f %.3f %d %.3f %.3f %.3f %.4f %.3f %.3f %.4f %.4f %.2f %d %.3f %.3f %.3f "
                    "%.4f %d %.2f %d %d %.5f %.2f %.2f %.2f %.2f %.2f %d %llu %llu\n",
                    agl, mapper->CellM(), st.known_cells, st.safe_cells / k, st.uncertain_cells / k,
                    st.slope_cells / k, st.rock_cells / k, acc.WithinSigma(1.0),
                    acc.WithinSigma(2.0), Quantile(acc.elev_sigma, 0.5),
                    Quantile(acc.elev_err, 0.5), Quantile(acc.slope_err, 0.5), se.valid,
                    se.median_abs, se.robust_sigma, se.rms_clipped, se.frac_over_1px,
                    m.site_valid ? 1 : 0, m.site_valid ? m.site_clearance_m : NAN, m.rocks_resolved,
                    m.rocks_detected, acc.Far(), se.corr[0], se.corr[1], se.corr[2], se.corr[3],
                    st.disparity_scale, st.calibration_landmarks,
                    static_cast<unsigned long long>(st.outliers_rejected),
                    static_cast<unsigned long long>(st.cells_replaced));
      return std::string(b);
    }();
    std::fputs(line.c_str(), dat);
    std::fputs(line.c_str(), stdout);
    std::fflush(stdout);
  }
  if (!dat_file.Commit(&why)) return Fail(why);
  if (frame_correlation) PrintFrameCorrelation(frame_errors);
  // Truth: how much of the final grid is a possible site (no truth hazard node within the
  // footprint radius, at least a footprint radius inside the grid).
  {
    const swf::sim::Terrain& t = world.Terrain();
    const swf::sim::HazardMap& h = world.Truth();
    const double r = eo.footprint_radius_m;
    const int rn = static_cast<int>(std::ceil(r / t.CellM()));
    const double half = 0.5 * mapper->GridCells() * mapper->CellM();
    const double cx = mapper->CornerX() + half;
    const double cy = mapper->CornerY() + half;
    int candidates = 0;
    int clear = 0;
    for (int j = 0; j < t.Size(); j += 2) {
      for (int i = 0; i < t.Size(); i += 2) {
        if (std::fabs(t.NodeX(i) - cx) > half - r || std::fabs(t.NodeY(j) - cy) > half - r) {
          continue;
        }
        ++candidates;
        bool hit = false;
        for (int b = std::max(0, j - rn); b <= std::min(t.Size() - 1, j + rn) && !hit; ++b) {
          for (int a = std::max(0, i - rn); a <= std::min(t.Size() - 1, i + rn); ++a) {
            if (h.hazard[static_cast<std::size_t>(b) * t.Size() + a] != 0 &&
                std::hypot(t.NodeX(a) - t.NodeX(i), t.NodeY(b) - t.NodeY(j)) <= r) {
              hit = true;
              break;
            }
          }
        }
        clear += !hit;
      }
    }
    std::printf(
        "truth: %d of %d candidate centres in the final grid are a footprint away from "
        "every true hazard\n",
        clear, candidates);
  }
  // Truth rocks above the threshold inside the final grid, with the map's sigma at their centre.
  for (const swf::sim::Rock& rock : world.Terrain().Rocks()) {
    int ci = 0;
    int cj = 0;
    if (rock.height_m < eo.max_rock_height_m ||
        !mapper->CellOf(rock.center_m.x(), rock.center_m.y(), &ci, &cj)) {
      continue;
    }
    const std::size_t c = static_cast<std::size_t>(cj) * mapper->GridCells() + ci;
    std::printf("rock at (%.2f, %.2f) height %.2f m diameter %.2f m: sigma %.3f m class %d\n",
                rock.center_m.x(), rock.center_m.y(), rock.height_m, rock.diameter_m,
                mapper->Sigma()[c], static_cast<int>(mapper->Classes()[c]));
  }
  std::string error;
  if (!DrawPublished(world, eo, "Hazard map of the flight descent", out + "/flight_map.png",
                     &error))
    return Fail(error);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "swf-hazard: hazard mapping evaluated on seeded simulated descents against the simulator's "
      "truth"};
  swf::ground_cli::Adopt(&app, "swf-hazard");
  app.require_subcommand(1);
  EvalOptions eo;
  eo.shared_dir = swf::ground_cli::SharedDir();
  // The options every command takes.
  const auto add_common = [&eo](CLI::App* cmd) {
    cmd->add_option("--shared", eo.shared_dir, "the shared data directory")->capture_default_str();
    cmd->add_option("--width", eo.image_width, "image width, px")
        ->capture_default_str()
        ->check(CLI::Range(1, 16384));
    cmd->add_option("--height", eo.image_height, "image height, px")
        ->capture_default_str()
        ->check(CLI::Range(1, 16384));
    cmd->add_option("--downsample", eo.downsample, "the hazard mapper's image reduction")
        ->capture_default_str()
        ->check(CLI::Range(1, 4));
  };
  eo.image_width = 512;
  eo.image_height = 384;
  eo.downsample = 1;
  std::string out;
  int descents = 17;
  int sweep_seeds = 3;
  std::string only_name;
  CLI::App* eval = app.add_subcommand(
      "eval",
      "altitude sweep over the three terrain presets, then seeded fused descents with the "
      "safe-site check -> OUTDIR/hazard_eval.json, *.dat, PNGs");
  eval->add_option("OUTDIR", out, "output directory (created)")->required();
  eval->add_option("--descents", descents, "fused descents per preset")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  eval->add_option("--sweep-seeds", sweep_seeds, "seeds of the altitude sweep")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  eval->add_option("--descent-preset", only_name, "fly the descents over this preset only")
      ->check(CLI::IsMember({"plains", "craters", "rocks"}));
  add_common(eval);
  std::string preset_name = "rocks";
  std::uint64_t seed = 1;
  CLI::App* map = app.add_subcommand("map", "one fused descent, the final hazard map as PNG");
  map->add_option("OUT", out, "the PNG to write (its directory is created)")->required();
  map->add_option("--preset", preset_name, "plains, craters or rocks")->capture_default_str();
  map->add_option("--seed", seed)->capture_default_str();
  add_common(map);
  double x = 0.0;
  double y = 0.0;
  double step = 5.0;
  int swf = 0;
  int relief_calibration = 0;
  int frame_correlation = 0;
  CLI::App* flight =
      app.add_subcommand("flight", "one descent flown with the mapper -> OUTDIR/flight.dat, PNG");
  flight->add_option("OUTDIR", out, "output directory (created)")->required();
  flight->add_option("--preset", preset_name, "plains, craters or rocks");
  flight->add_option("--seed", seed)->capture_default_str();
  flight->add_option("--terrain-size", eo.terrain_size, "terrain grid nodes a side (default 2048)")
      ->check(CLI::PositiveNumber);
  flight->add_option("--x", x, "landing point x, m")->capture_default_str();
  flight->add_option("--y", y, "landing point y, m")->capture_default_str();
  flight->add_option("--step", step, "descent step, m")->capture_default_str();
  flight->add_option("--swf", swf, "1: poses from swf-eval's filter")->capture_default_str();
  flight
      ->add_option("--relief-calibration", relief_calibration,
                   "1: print the relief sigma's calibration on rock-free cells per update "
                   "(fused and single-frame; renders each pair twice)")
      ->capture_default_str();
  flight
      ->add_option("--frame-correlation", frame_correlation,
                   "1: print the correlation of single-frame relief errors between every two "
                   "frames of one cell size (renders each pair twice)")
      ->capture_default_str();
  flight
      ->add_option("--pose-sigma-per-altitude", eo.pose_sigma_per_altitude,
                   "position sigma per axis given to the mapper, fraction of altitude")
      ->capture_default_str();
  add_common(flight);
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue) {
    return code;
  }
  swf::cli::RemovePartialOutputsOnSignal();
  if (eval->parsed()) {
    swf::sim::TerrainPreset only = swf::sim::TerrainPreset::kCraterField;
    const bool restrict =
        !only_name.empty() && swf::sim::ParseTerrainPreset(only_name.c_str(), &only);
    return Eval(out, eo, descents, sweep_seeds, restrict ? static_cast<int>(only) : -1);
  }
  if (flight->parsed() && flight->count("--preset") == 0) preset_name = "craters";
  if (flight->parsed() && flight->count("--terrain-size") == 0) eo.terrain_size = 2048;
  swf::sim::TerrainPreset preset = swf::sim::TerrainPreset::kRockField;
  if (!swf::sim::ParseTerrainPreset(preset_name.c_str(), &preset)) {
    return Fail("unknown --preset " + preset_name.substr(0, 40) + " (plains, craters or rocks)");
  }
  if (map->parsed()) return Map(out, eo, preset, seed);
  return Flight(out, eo, preset, seed, x, y, step, swf != 0, relief_calibration != 0,
                frame_correlation != 0);
}
