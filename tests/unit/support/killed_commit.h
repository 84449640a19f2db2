// A commit of WriteTogetherAtomic killed or paused half-way, for the tests of what a reader does.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
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

// A commit (a call that ends in WriteTogetherAtomic) in a forked child, paused right after its
// first rename until Resume() or Kill(): a live writer in the middle of its renames. The
// constructor returns once the child is paused there, or has died before (Paused() false).
class PausedCommit {
 public:
  explicit PausedCommit(const std::function<void()>& commit) {
    if (pipe(paused_) != 0 || pipe(resume_) != 0) std::abort();
    pid_ = fork();
    if (pid_ < 0) std::abort();
    if (pid_ == 0) {
      close(paused_[0]);  // a dead test runner ends the child's wait (end of file)
      close(resume_[1]);
      const int paused = paused_[1], resume = resume_[0];
      SetAfterRenameHookForTest([paused, resume](size_t renamed) {
        char c = 0;
        if (renamed == 1 && (write(paused, "p", 1) != 1 || read(resume, &c, 1) != 1)) _exit(3);
      });
      try {  // never back into the test runner inside the child
        commit();
      } catch (...) {
        _exit(2);
      }
      _exit(0);
    }
    close(paused_[1]);
    close(resume_[0]);
    char c = 0;
    ssize_t n;
    while ((n = read(paused_[0], &c, 1)) < 0 && errno == EINTR) {
    }
    paused_now_ = n == 1;
    close(paused_[0]);
  }
  ~PausedCommit() {
    Resume();
    Finished();
  }
  PausedCommit(const PausedCommit&) = delete;
  PausedCommit& operator=(const PausedCommit&) = delete;

  bool Paused() const { return paused_now_; }
  // Lets the commit finish (nothing when the child is no longer waiting).
  void Resume() {
    if (resume_[1] < 0) return;
    if (paused_now_) {
      void (*old)(int) = signal(SIGPIPE, SIG_IGN);  // a child gone since: no signal to the runner
      if (write(resume_[1], "r", 1) != 1) {
      }
      signal(SIGPIPE, old);
    }
    close(resume_[1]);
    resume_[1] = -1;
  }
  // A kill -9 of the paused writer, in the middle of its renames.
  void Kill() {
    if (pid_ > 0) kill(pid_, SIGKILL);
  }
  // Waits for the child; true when its commit completed (exit 0).
  bool Finished() {
    if (pid_ > 0) {
      int status = 0;
      while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
      }
      pid_ = -1;
      completed_ = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    }
    return completed_;
  }

 private:
  int paused_[2] = {-1, -1}, resume_[2] = {-1, -1};
  pid_t pid_ = -1;
  bool paused_now_ = false, completed_ = false;
};

}  // namespace mvtm::test
