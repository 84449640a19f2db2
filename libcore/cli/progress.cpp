#include "cli/progress.h"

#include <unistd.h>

#include <cstdio>

namespace mvtm {

bool StderrIsTerminal() { return isatty(2) == 1; }

Progress::Progress(std::string label, size_t total, bool quiet)
    : label_(std::move(label)),
      total_(total),
      enabled_(!quiet && total > 0 && StderrIsTerminal()) {}

Progress::~Progress() {
  if (enabled_ && last_percent_ >= 0) std::fputs("\n", stderr);
}

void Progress::Step(size_t n) {
  done_ += n;
  if (!enabled_) return;
  int percent = static_cast<int>(100 * done_ / total_);
  if (percent == last_percent_) return;
  last_percent_ = percent;
  const int width = 30;
  int fill = percent * width / 100;
  std::fprintf(stderr, "\r%s [%.*s%*s] %3d%% %zu/%zu", label_.c_str(), fill,
               "##############################", width - fill, "", percent, done_, total_);
  std::fflush(stderr);
}

}  // namespace mvtm
