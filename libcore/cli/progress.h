// mvtm — progress on a terminal: a one-line bar on stderr, drawn only when stderr is a terminal
// and the tool is not quiet (never in logs, pipes or batch jobs).
#pragma once

#include <cstddef>
#include <string>

namespace mvtm {

// True when stderr is a terminal.
bool StderrIsTerminal();

// A single-line progress bar on stderr. Not thread-safe: step it from one thread.
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
