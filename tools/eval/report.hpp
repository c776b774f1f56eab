// Words and JSON for sequence runs (EuRoC, KITTI), computed from the numbers: a run that failed
// (input refused, non-finite, diverged, frames without a tracked landmark) has no score, its
// accuracy fields are null with the reason, and it is never compared with another run; two
// scored runs are compared by their measured ratio.
#pragma once

#include <string>
#include <vector>

#include "json.hpp"
#include "sequence.hpp"

namespace swf::eval {

// The run as a JSON object (accuracy fields null with "<field>_reason" unless the run is ok).
// `trajectory`: the file the estimate was written to ("" = none).
Json RunJson(const RunRecord& run, const StereoSequence& sequence, const std::string& trajectory);

// Markdown table of the runs: verdict, ATE, final anchored error, relative errors, tracks.
std::string RunsTable(const std::vector<RunRecord>& runs);

// One sentence comparing `value_a` of run a with `value_b` of run b, e.g. the ATE ("ATE"):
// the ratio when both runs are ok, otherwise why they are not compared.
std::string CompareSentence(const RunRecord& a, double value_a, const RunRecord& b, double value_b,
                            const std::string& what);

// "SWF(5) diverged at frame 412 [...]: ..." for every failed run, "" when all are ok.
std::string FailureSentences(const std::vector<RunRecord>& runs);

// Per run: frames per integrity status, and VALID frames whose error exceeded the protection
// level (the navigation output was wrong without saying so).
std::string IntegritySentences(const std::vector<RunRecord>& runs);

bool AllOk(const std::vector<RunRecord>& runs);

// Formats like printf into a std::string.
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace swf::eval
