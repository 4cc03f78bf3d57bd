#pragma once
// Child processes for work that must not take its caller down when it crashes (one evaluation run
// of a benchmark suite): start a command with stdout and stderr going to a log file, then wait for
// whichever child ends first.

#include <sys/types.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace voca::platform {

// How a child ended: its exit code, or the signal that killed it.
struct ChildExit {
  pid_t pid = -1;
  int exit_code = -1;  // valid when signal == 0
  int signal = 0;      // non-zero: killed by this signal (a crash or a kill)

  bool succeeded() const { return signal == 0 && exit_code == 0; }
};

// Starts argv[0] (searched on PATH when it has no slash) with argv, stdin from /dev/null and stdout
// plus stderr appended to log_file. Throws RuntimeFailure when it cannot be started.
pid_t startChild(const std::vector<std::string>& argv, const std::filesystem::path& log_file);

// Blocks until one of this process's children ends and reports it. Throws RuntimeFailure when
// there is no child to wait for.
ChildExit waitForAnyChild();

// The exit of child pid if it has ended, without blocking (nullopt while it runs), for callers that
// report progress while they wait. Throws RuntimeFailure when pid is not a child of this process.
std::optional<ChildExit> pollChild(pid_t pid);

// How a forked copy of this process ended (runForked), with what it wrote to its stderr.
struct ForkedRun {
  ChildExit exit;
  std::string output;  // the copy's stderr, at most its first 64 KiB
};

// Runs `work` in a forked copy of this process and waits for the copy to end; its exit code is
// work()'s return value (1 when work throws). For a library call that may corrupt the heap when it
// fails, to learn whether it succeeds without that happening here. The copy has only the calling
// thread, so `work` must not need a lock another thread may hold: call it where no other thread of
// this process runs library code. Throws RuntimeFailure when the copy cannot be made.
ForkedRun runForked(const std::function<int()>& work);

// The running program's own executable (to start more of itself), from /proc/self/exe; falls back
// to the given argv0 when /proc is not mounted.
std::filesystem::path currentExecutable(const std::string& argv0 = "voca");

// "voca: exit code 1", "killed by signal 11 (Segmentation fault)".
std::string describeExit(const ChildExit& exit);

}  // namespace voca::platform
