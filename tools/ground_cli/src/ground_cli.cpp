#include "swf/ground_cli/ground_cli.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>

namespace swf::ground_cli {

void Adopt(CLI::App* app, const char* tool) {
  app->name(tool);  // messages name the program, not the path it was started by
  app->set_version_flag("--version", cli::VersionLine(tool), "the version and the commit");
  app->footer("exit: 0 ok, 1 failed, 2 usage or configuration refused, 3 degraded (docs/cli.md)");
}

namespace {

bool Knows(const CLI::App& app, const std::string& name) {
  if (app.get_option_no_throw(name) != nullptr) return true;
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (Knows(*sub, name)) return true;
  }
  return false;
}

bool IsSubcommand(const CLI::App& app, const std::string& name) {
  for (const CLI::App* sub : app.get_subcommands({})) {
    if (sub->check_name(name)) return true;
  }
  return false;
}

// The first option on the command line that neither the program nor any subcommand declares:
// named before a missing required option (CLI11 checks requirements first), since it is usually
// the cause. "" when there is none.
std::string UnknownOption(const CLI::App& app, int argc, char** argv) {
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--") break;
    if (arg.size() < 2 || arg[0] != '-' || (arg[1] != '-' && std::isdigit(arg[1]) != 0)) continue;
    const std::string name = arg.substr(0, arg.find('='));
    if (!Knows(app, name)) return name;
  }
  return "";
}

}  // namespace

int Parse(CLI::App* app, int argc, char** argv) {
  try {
    app->parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::fputs(app->help().c_str(), stdout);
    return cli::kExitOk;
  } catch (const CLI::CallForAllHelp&) {
    std::fputs(app->help("", CLI::AppFormatMode::All).c_str(), stdout);
    return cli::kExitOk;
  } catch (const CLI::CallForVersion& e) {
    std::printf("%s\n", e.what());
    return cli::kExitOk;
  } catch (const CLI::ParseError& e) {
    const std::string unknown = UnknownOption(*app, argc, argv);
    std::string why = unknown.empty() ? e.what() : "unknown option " + unknown;
    if (unknown.empty() && app->get_require_subcommand_min() > 0 && argc > 1 && argv[1][0] != '-' &&
        !IsSubcommand(*app, argv[1])) {
      why = std::string("unknown command '") + argv[1] + "' (";
      for (const CLI::App* sub : app->get_subcommands({})) {
        why += (why.back() == '(' ? "" : ", ") + sub->get_name();
      }
      why += ")";
    }
    std::fprintf(stderr, "%s: %s (usage: %s --help)\n", app->get_name().c_str(), why.c_str(),
                 app->get_name().c_str());
    return cli::kExitUsage;
  }
  return cli::kContinue;
}

namespace {

nlohmann::json OptionsOf(const CLI::App& app) {
  nlohmann::json options = nlohmann::json::object();
  for (const CLI::Option* o : app.get_options()) {
    const std::string name = o->get_single_name();
    if (name == "help" || name == "version" || name == "help-all") continue;
    if (o->count() > 0) {
      const std::vector<std::string>& given = o->results();
      if (o->get_expected_max() > 1) {
        options[name] = given;
      } else if (o->get_type_size() == 0) {
        options[name] = true;  // a flag
      } else {
        options[name] = given.empty() ? "" : given.back();
      }
    } else if (!o->get_default_str().empty()) {
      options[name] = o->get_default_str();
    } else if (o->get_type_size() == 0) {
      options[name] = false;
    } else {
      options[name] = nullptr;
    }
  }
  for (const CLI::App* sub : app.get_subcommands()) {
    options[sub->get_name()] = OptionsOf(*sub);
  }
  return options;
}

}  // namespace

nlohmann::json RunEcho(const CLI::App& app, const char* tool, int argc, char** argv) {
  nlohmann::json arguments = nlohmann::json::array();
  for (int a = 1; a < argc; ++a) arguments.push_back(argv[a]);
  return {{"tool", tool},
          {"version", cli::Version()},
          {"commit", cli::Commit()},
          {"arguments", arguments},
          {"options", OptionsOf(app)}};
}

namespace {

// The document's text with its newline; invalid UTF-8 replaced (dump() would throw on it).
template <typename Document>
std::string TextOf(const Document& document, int indent) {
  return document.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace

bool WriteJson(const std::string& path, const nlohmann::json& document, std::string* error,
               int indent) {
  return cli::WriteFileAtomically(path, TextOf(document, indent), error);
}

bool WriteJson(const std::string& path, const nlohmann::ordered_json& document, std::string* error,
               int indent) {
  return cli::WriteFileAtomically(path, TextOf(document, indent), error);
}

void PrintJson(const nlohmann::json& document, int indent) {
  std::fputs(TextOf(document, indent).c_str(), stdout);
}

void PrintJson(const nlohmann::ordered_json& document, int indent) {
  std::fputs(TextOf(document, indent).c_str(), stdout);
}

nlohmann::json Number(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

}  // namespace swf::ground_cli
