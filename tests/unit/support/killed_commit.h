// A commit of WriteTogetherAtomic killed half-way, for the tests of what the next reader does.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <functional>

#include "base/atomic_file.h"

namespace mvtm::test {

// Runs `commit` (a call that ends in WriteTogetherAtomic) in a forked child that a hook kills with
// SIGKILL right after its first rename (as a kill -9 arriving there would); true when the child
// died so. The child never returns into the test runner.
inline bool CommitKilledAfterFirstRename(const std::function<void()>& commit) {
  const pid_t pid = fork();
  if (pid == 0) {
    SetAfterRenameHookForTest([](size_t renamed) {
      if (renamed == 1) raise(SIGKILL);
    });
    try {
      commit();
    } catch (...) {
      _exit(2);
    }
    _exit(0);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

}  // namespace mvtm::test
