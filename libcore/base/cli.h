// mvtm — the common frame of every tool's main().
//
// RunMain() sets the classic "C" locale for the whole process, parses the command line with
// CLI11 (one declarative option table per tool gives --help), runs the tool and maps exceptions
// to exit statuses and one-line messages on stderr:
//   0 success; 1 Error (data, I/O); 2 UsageError or a command-line error.
// Tools with verdicts (ssim) may return further documented codes from `run`.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace mvtm {

// Creates an App with mvtm's conventions: `--version`, a footer pointing at the man page.
void ConfigureApp(CLI::App& app, const std::string& tool, const std::string& description);

int RunMain(CLI::App& app, const std::string& tool, int argc, char** argv,
            const std::function<int()>& run);

// True when stderr is a terminal (progress bars are shown only then).
bool StderrIsTerminal();

// A single-line progress bar on stderr, drawn only when stderr is a terminal and not quiet.
class Progress {
 public:
  Progress(std::string label, size_t total, bool quiet);
  ~Progress();
  void Step(size_t n = 1);

 private:
  std::string label_;
  size_t total_, done_ = 0;
  bool enabled_;
  int last_percent_ = -1;
};

}  // namespace mvtm
