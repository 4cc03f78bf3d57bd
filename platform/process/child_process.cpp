#include "platform/process/child_process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

#include <fmt/core.h>

#include "voca/core/error.h"

extern char** environ;

namespace voca::platform {

namespace {

ChildExit decodeStatus(pid_t pid, int status) {
  ChildExit exit;
  exit.pid = pid;
  if (WIFEXITED(status)) {
    exit.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    exit.signal = WTERMSIG(status);
  }
  return exit;
}

}  // namespace

pid_t startChild(const std::vector<std::string>& argv, const std::filesystem::path& log_file) {
  if (argv.empty()) throw RuntimeFailure("startChild: empty command");
  std::vector<char*> args;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_file.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  const int error = argv[0].find('/') == std::string::npos
                        ? posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ)
                        : posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) {
    throw RuntimeFailure(fmt::format("cannot start {} (log {}): {}", argv[0], log_file.string(), std::strerror(error)));
  }
  return pid;
}

ChildExit waitForAnyChild() {
  int status = 0;
  pid_t pid = -1;
  do {
    pid = ::waitpid(-1, &status, 0);
  } while (pid < 0 && errno == EINTR);
  if (pid < 0) throw RuntimeFailure(fmt::format("waiting for a child process: {}", std::strerror(errno)));
  return decodeStatus(pid, status);
}

std::optional<ChildExit> pollChild(pid_t pid) {
  int status = 0;
  pid_t ended = -1;
  do {
    ended = ::waitpid(pid, &status, WNOHANG);
  } while (ended < 0 && errno == EINTR);
  if (ended < 0) throw RuntimeFailure(fmt::format("waiting for child process {}: {}", pid, std::strerror(errno)));
  if (ended == 0) return std::nullopt;
  return decodeStatus(ended, status);
}

ForkedRun runForked(const std::function<int()>& work) {
  std::array<int, 2> pipe_ends{};
  // Close-on-exec: a process another thread starts meanwhile must not hold the write end, or the read
  // below would wait for that process to end. dup2 clears the flag on the copy's stderr.
  if (::pipe2(pipe_ends.data(), O_CLOEXEC) != 0)
    throw RuntimeFailure(fmt::format("cannot create a pipe: {}", std::strerror(errno)));
  std::fflush(nullptr);  // else the copy would write this process's buffered output a second time
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(pipe_ends[0]);
    ::close(pipe_ends[1]);
    throw RuntimeFailure(fmt::format("cannot fork: {}", std::strerror(error)));
  }
  if (pid == 0) {
    ::close(pipe_ends[0]);
    ::dup2(pipe_ends[1], STDERR_FILENO);
    ::close(pipe_ends[1]);
    int code = 1;
    try {
      code = work();
    } catch (...) {
      code = 1;
    }
    std::fflush(nullptr);
    ::_exit(code);  // no exit handlers or destructors: they belong to the original process
  }
  ::close(pipe_ends[1]);
  ForkedRun run;
  constexpr std::size_t kMaxOutput = 64 * 1024;
  std::array<char, 4096> buffer{};
  while (true) {
    const ssize_t got = ::read(pipe_ends[0], buffer.data(), buffer.size());
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;
    const std::size_t room = kMaxOutput - std::min(kMaxOutput, run.output.size());
    run.output.append(buffer.data(), std::min(room, static_cast<std::size_t>(got)));
  }
  ::close(pipe_ends[0]);
  int status = 0;
  pid_t ended = -1;
  do {
    ended = ::waitpid(pid, &status, 0);
  } while (ended < 0 && errno == EINTR);
  if (ended < 0) throw RuntimeFailure(fmt::format("waiting for a forked copy: {}", std::strerror(errno)));
  run.exit = decodeStatus(pid, status);
  return run;
}

std::filesystem::path currentExecutable(const std::string& argv0) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::filesystem::path(argv0) : self;
}

std::string describeExit(const ChildExit& exit) {
  if (exit.signal != 0) return fmt::format("killed by signal {} ({})", exit.signal, ::strsignal(exit.signal));
  return fmt::format("exit code {}", exit.exit_code);
}

}  // namespace voca::platform
