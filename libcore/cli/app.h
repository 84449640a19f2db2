// mvtm — the common frame of every tool's main() (the only module that knows CLI11).
//
// RunMain() sets the classic "C" locale for the whole process, parses the command line with
// CLI11 (one declarative option table per tool gives --help), runs the tool and maps exceptions
// to exit statuses and one-line messages on stderr:
//   0 success; 1 Error (data, I/O); 2 UsageError or a command-line error.
// Tools with verdicts (ssim) may return further documented codes from `run`.
// CLI11 is only declared here: a tool's main() that calls RunTool does not parse CLI11's
// headers (8-15 s of compile time each).
#pragma once

#include <functional>
#include <string>

#include "run/option_table.h"

namespace CLI {
class App;
}

namespace mvtm {

// Creates an App with mvtm's conventions: `--version`, a footer pointing at the man page.
void ConfigureApp(CLI::App& app, const std::string& tool, const std::string& description);

int RunMain(CLI::App& app, const std::string& tool, int argc, char** argv,
            const std::function<int()>& run);

// A tool's whole main() around its declared option table: an App named after table.tool(),
// described by `description` (and `footer` when the exit statuses need more than the common
// three), the table put into it (AddOptionTable), then RunMain.
int RunTool(OptionTable table, const std::string& description, int argc, char** argv,
            const std::function<int()>& run, const std::string& footer = "");

}  // namespace mvtm
