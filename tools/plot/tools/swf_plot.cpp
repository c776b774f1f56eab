// swf-plot: the plots of a run drawn from its LCM logs (a replay's output log with the simulated
// descent's log that holds the truth, or a campaign run's log): the messages go to
// evaluation::RunJudge, the judge swf-sil runs live, and the pictures are swf::plot's, the same
// swf-sil draws into summary.plot_dir.
//   swf-plot RUN.lcmlog [MORE.lcmlog ...] --out DIR [--footprint-radius M]
// Exit (docs/cli.md): 0 every plot the logs allow was drawn; 1 a log is unreadable, no navigation
// output has its truth, or a plot failed (each failure named on stderr); 2 usage.
//
// `swf-plot curves` draws line charts stored as text (swf::plot::ReadLineChart: swf-eval's
// OUT/NAME.dat, which carry their title, axis labels and scale), each as NAME.png:
//   swf-plot curves FILE.dat [MORE.dat ...] [--out DIR]     (default: beside each file)
// Exit: 0 every chart drawn; 1 a file is unreadable or malformed (named with its line) or a chart
// failed to draw. Every file is tried either way.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "swf/evaluation/run_judge.hpp"
#include "swf/ground_cli/ground_cli.hpp"
#include "swf/hazard/hazard_mapper.hpp"
#include "swf/plot/plot.hpp"

namespace {

// `swf-plot curves`: each file's chart into DIR/NAME.png (beside the file when DIR is empty).
int DrawCurves(const std::vector<std::string>& files, const std::string& out_dir) {
  int rc = 0;
  for (const std::string& file : files) {
    std::string error;
    swf::plot::LineChart chart;
    if (!swf::plot::ReadLineChart(file, &chart, &error)) {
      std::fprintf(stderr, "swf-plot curves: %s\n", error.c_str());
      rc = swf::cli::kExitFailed;
      continue;
    }
    const std::filesystem::path path(file);
    const std::filesystem::path dir =
        out_dir.empty() ? path.parent_path() : std::filesystem::path(out_dir);
    const std::string png = (dir / path.stem()).string() + ".png";
    if (!swf::plot::DrawLineChart(chart, png, &error)) {
      std::fprintf(stderr, "swf-plot curves: cannot draw %s\n", error.c_str());
      rc = swf::cli::kExitFailed;
      continue;
    }
    std::printf("%s\n", png.c_str());
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "swf-plot: a run's plots (trajectory, attitude error, landmark error, landmark map, hazard "
      "map) from its LCM logs: the estimates and the truth recorded beside them"};
  std::vector<std::string> logs;
  std::string out;
  double footprint_radius_m = swf::hazard::HazardMapperOptions{}.footprint_radius_m;
  // Not ->required(): a required option of the app would be required with `curves` too.
  app.add_option("logs", logs, "LCM logs: the run's outputs and the truth (any order; required)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", out, "directory the PNGs are written to (required; created)");
  app.add_option("--footprint-radius", footprint_radius_m,
                 "lander footprint radius drawn around the safe site (m; 0: none)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  CLI::App* curves = app.add_subcommand(
      "curves", "line charts stored as text (swf-eval's OUT/NAME.dat), each drawn as NAME.png");
  std::vector<std::string> dat_files;
  std::string curves_out;
  curves->add_option("files", dat_files, "the charts' text files (.dat)")
      ->required()
      ->check(CLI::ExistingFile);
  curves->add_option("--out", curves_out,
                     "directory the PNGs are written to (default: beside "
                     "each file; created)");
  swf::ground_cli::Adopt(&app, "swf-plot");
  if (const int code = swf::ground_cli::Parse(&app, argc, argv); code != swf::cli::kContinue)
    return code;
  if (!curves->parsed() && (logs.empty() || out.empty())) {
    std::fprintf(stderr,
                 "swf-plot: give the run's LCM logs and --out DIR (or: swf-plot curves FILE.dat) "
                 "(usage: swf-plot --help)\n");
    return swf::cli::kExitUsage;
  }
  const std::string& out_dir = curves->parsed() ? curves_out : out;
  if (std::string error; !out_dir.empty() && !swf::cli::MakeDirectories(out_dir, &error)) {
    std::fprintf(stderr, "swf-plot: %s\n", error.c_str());
    return swf::cli::kExitFailed;
  }
  if (curves->parsed()) return DrawCurves(dat_files, curves_out);

  swf::evaluation::RunJudge judge;
  swf::evaluation::LogTally tally;
  if (std::string error; !swf::evaluation::JudgeLogs(logs, &judge, &tally, &error)) {
    std::fprintf(stderr, "swf-plot: %s\n", error.c_str());
    return swf::cli::kExitFailed;
  }
  const swf::evaluation::RunScore score = judge.Score();
  if (score.outputs.empty()) {
    std::fprintf(stderr, "swf-plot: %s\n",
                 score.navs_without_truth > 0
                     ? "no navigation output has the truth of its frame: give the log with the "
                       "truth (SIM_TRUTH) too"
                     : "no navigation output in the logs");
    return swf::cli::kExitFailed;
  }
  const swf::evaluation::HazardMapView hazard = swf::evaluation::ViewOf(tally.last_hazard_map);
  swf::plot::RunPictures pictures;
  pictures.last_hazard_map = tally.has_hazard_map ? &hazard : nullptr;
  pictures.footprint_radius_m = footprint_radius_m;
  std::vector<std::string> errors;
  const std::vector<std::string> written = swf::plot::DrawRun(score, pictures, out, &errors);
  for (const std::string& png : written) std::printf("%s\n", png.c_str());
  for (const std::string& e : errors) std::fprintf(stderr, "swf-plot: cannot draw %s\n", e.c_str());
  return errors.empty() ? 0 : 1;
}
