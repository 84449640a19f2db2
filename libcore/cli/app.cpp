#include "cli/app.h"

#include <CLI/CLI.hpp>
#include <clocale>
#include <filesystem>
#include <iostream>
#include <locale>
#include <new>
#include <string>

#include "base/error.h"
#include "base/version.h"
#include "cli/options.h"

namespace mvtm {

void ConfigureApp(CLI::App& app, const std::string& tool, const std::string& description) {
  app.name(tool);
  app.description(description);
  app.set_version_flag("--version", std::string(tool) + " (mvtm) " + kVersion);
  app.footer("See man " + tool +
             " for details. Exit status: 0 success, 1 data or I/O error, 2 usage error.");
  app.get_formatter()->column_width(34);
}

int RunTool(OptionTable table, const std::string& description, int argc, char** argv,
            const std::function<int()>& run, const std::string& footer) {
  CLI::App app;
  ConfigureApp(app, table.tool(), description);
  if (!footer.empty()) app.footer(footer);
  AddOptionTable(app, table);
  return RunMain(app, table.tool(), argc, argv, run);
}

namespace {

// CLI11's words for a flag given a value ("no-flow was given a disallowed flag override") in the
// tools' own form, "--no-flow: a flag takes no value"; other parse errors as CLI11 words them.
std::string ParseErrorText(const std::string& what) {
  const std::string tag = " was given a disallowed flag override";
  const size_t at = what.find(tag);
  if (at == std::string::npos || at == 0) return what;
  return "--" + what.substr(0, at) + ": a flag takes no value";
}

// The first "--FLAG=VALUE" on the command line whose FLAG is a flag of the tool's table, "" when
// none: CLI11 refuses a flag's value but its own "true" (disable_flag_override), so
// "--no-flow=true" would pass as "on"; every value is refused instead, before parsing.
std::string FlagGivenValue(int argc, char** argv) {
  const OptionTable* table = CommandLineTable();
  if (!table) return "";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    const size_t eq = arg.find('=');
    if (arg.rfind("--", 0) != 0 || eq == std::string::npos) continue;
    for (const OptionSpec& s : table->options())
      if (s.is_flag && s.flag == arg.substr(0, eq)) return s.flag;
  }
  return "";
}

}  // namespace

int RunMain(CLI::App& app, const std::string& tool, int argc, char** argv,
            const std::function<int()>& run) {
  std::setlocale(LC_ALL, "C");
  std::locale::global(std::locale::classic());
  try {
    try {
      if (const std::string flag = FlagGivenValue(argc, argv); !flag.empty()) {
        std::cerr << tool << ": error: " << flag << ": a flag takes no value (try --help)\n";
        return 2;
      }
      app.parse(argc, argv);
    } catch (const CLI::CallForHelp&) {
      std::cout << app.help();
      return 0;
    } catch (const CLI::CallForAllHelp&) {
      std::cout << app.help("", CLI::AppFormatMode::All);
      return 0;
    } catch (const CLI::CallForVersion&) {
      std::cout << app.version() << "\n";
      return 0;
    } catch (const CLI::Success&) {
      return 0;  // a flag that printed what was asked (--options-json)
    } catch (const CLI::ParseError& e) {
      std::cerr << tool << ": error: " << ParseErrorText(e.what()) << " (try --help)\n";
      return 2;
    }
    return run();
  } catch (const FieldError& e) {
    // A library names its options struct's field; the user knows the flag that set it.
    const OptionTable* t = CommandLineTable();
    const std::string flag = t ? t->FlagOfField(e.field()) : "";
    std::cerr << tool << ": error: " << (flag.empty() ? e.field() : flag) << ": " << e.problem()
              << "\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 2;
  } catch (const Error& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    // The library's text is "filesystem error: status: ... [PATH]"; say it mvtm's way.
    std::string where = e.path1().empty() ? "" : e.path1().string() + ": ";
    std::cerr << tool << ": error: " << where << e.code().message() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << tool << ": error: out of memory (an input larger than this machine can hold?)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace mvtm
