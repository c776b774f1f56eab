// The command-line convention (docs/cli.md) for the ground tools, on CLI11: the same --help,
// --version, refusals and exit codes as the flight processes' parser (swf::cli), the run echoed
// into every summary, JSON written whole through swf::cli::OutputFile or printed, and where the
// shared data is (SharedDir(), shared_dir.hpp).
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "swf/cli/cli.hpp"
#include "swf/ground_cli/shared_dir.hpp"

namespace swf::ground_cli {

// --version (the version and the commit) and the exit-code table in the help's footer.
void Adopt(CLI::App* app, const char* tool);

// CLI11's parse with the convention's answers: cli::kContinue when the program goes on;
// cli::kExitOk after --help / --version (printed on stdout); cli::kExitUsage (2, not CLI11's own
// 1xx codes) with one line naming the problem on stderr for an unknown option, a missing or bad
// value, a missing required option or subcommand.
int Parse(CLI::App* app, int argc, char** argv);

// What every summary echoes: {"tool", "version", "commit", "arguments": [...], "options": {name:
// value, ...}} with every option's value as parsed or its default (those declared with
// capture_default_str), subcommands nested under their names.
nlohmann::json RunEcho(const CLI::App& app, const char* tool, int argc, char** argv);

// A JSON document, dumped with `indent`, into `path` through swf::cli::OutputFile (directories
// created, whole or not at all). JSON has no inf or nan: nlohmann writes them as null; bytes that
// are not UTF-8 (a path from the command line) are replaced, not thrown on.
bool WriteJson(const std::string& path, const nlohmann::json& document, std::string* error,
               int indent = 2);
// The same for a document whose fields keep their insertion order.
bool WriteJson(const std::string& path, const nlohmann::ordered_json& document, std::string* error,
               int indent = 2);

// A summary on stdout: the document dumped with `indent` (-1: on one line) and a newline, with the
// same replacement of bytes that are not UTF-8 as WriteJson (an argument echoed by RunEcho).
void PrintJson(const nlohmann::json& document, int indent = 2);
void PrintJson(const nlohmann::ordered_json& document, int indent = 2);

// A finite number, or null (JSON has no inf/nan).
nlohmann::json Number(double value);

}  // namespace swf::ground_cli
