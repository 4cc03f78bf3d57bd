#pragma once
// Helpers shared by the test suites: the shared reference data, running the `voca` binary, scratch
// folders, text files and error messages.

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <string_view>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <thread>

#include "voca/core/error.h"

extern char** environ;

namespace voca::test {

// Test cases that could not run because ../shared/data is absent. The test main turns a run with
// any of them (and no failure) into CTest's skip code, so the suite reports SKIPPED, not passed.
inline int& sharedDataSkips() {
  static int count = 0;
  return count;
}

// The exit code CTest reads as "skipped" (SKIP_RETURN_CODE in tests/CMakeLists.txt).
inline constexpr int kSkipReturnCode = 77;

// The sanitizer this build is instrumented with: "address" (ASan + UBSan), "thread" or "" (none).
// Sanitized code runs 5-15x slower; long checks that are about threads or memory, not numbers, may
// run on a shorter input there.
inline constexpr std::string_view kSanitizer = VOCA_TEST_SANITIZER;

// True when running in CI, where ../shared/data is always present and its absence is a failure.
inline bool runningInCi() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

// A file or folder under ../shared/data, or nullopt when the shared data is not beside the
// checkout (the project must build and pass without it): the caller returns early and the
// executable reports itself skipped. In CI a missing file fails the test instead.
// VOCA_SHARED_DATA in the environment replaces the folder found at configure time.
inline std::optional<std::filesystem::path> sharedData(const std::string& relative) {
  const char* override_dir = std::getenv("VOCA_SHARED_DATA");
  const std::filesystem::path root =
      override_dir != nullptr && *override_dir != '\0' ? override_dir : VOCA_SHARED_DATA_DIR;
  const std::filesystem::path path = root / relative;
  if (!std::filesystem::exists(path)) {
    if (runningInCi()) FAIL("shared data missing in CI (CI=true): " << path.string());
    MESSAGE("SKIPPED: shared data not found at " << path.string());
    ++sharedDataSkips();
    return std::nullopt;
  }
  return path;
}

// Runs the built `voca` binary with the given arguments, output discarded. Returns std::system's
// status: the exit code shifted left by 8 on Linux, 0 on success.
inline int runVoca(const std::string& args) {
  const std::string command = std::string(VOCA_BINARY_DIR) + "/bin/voca " + args + " >/dev/null 2>&1";
  return std::system(command.c_str());
}

// Renders a synthetic sequence as test input: `voca synth --out <out> <args>`, output discarded;
// returns std::system's status like runVoca. VOCA_TEST_SYNTH may name another voca to render with:
// tools/test.sh points the ThreadSanitizer stage at the Release build, where rendering is ten times
// faster, because there the sequence is only input (the renderer's own threads are checked under
// TSan by test_synth_e2e's fisheye case).
inline int renderSynth(const std::filesystem::path& out, const std::string& args) {
  const char* other = std::getenv("VOCA_TEST_SYNTH");
  const std::string voca = other != nullptr && *other != '\0' ? other : std::string(VOCA_BINARY_DIR) + "/bin/voca";
  const std::string command = voca + " synth --out " + out.string() + " " + args + " >/dev/null 2>&1";
  return std::system(command.c_str());
}

// What a command printed (stdout and stderr together) and its exit code.
struct CommandOutput {
  int exit_code = -1;
  std::string text;
};

// Runs the built `voca` binary with the given arguments and returns its exit code (not shifted)
// and everything it printed, so a test can check what a user would read.
inline CommandOutput runVocaOutput(const std::string& args) {
  std::random_device seed;
  const std::filesystem::path log =
      std::filesystem::path(VOCA_BINARY_DIR) / "test-scratch" / ("voca-output-" + std::to_string(seed()) + ".log");
  std::filesystem::create_directories(log.parent_path());
  const std::string command = std::string(VOCA_BINARY_DIR) + "/bin/voca " + args + " >" + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  CommandOutput result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log, std::ios::binary);
  result.text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  in.close();
  std::error_code ignored;
  std::filesystem::remove(log, ignored);
  return result;
}

// Starts the built `voca` binary in the background (TMPDIR set to tmpdir, everything it prints to
// log) and returns its process id; waitExitCode collects it.
inline pid_t spawnVoca(const std::string& args, const std::filesystem::path& tmpdir, const std::filesystem::path& log) {
  const std::string command = "TMPDIR=" + tmpdir.string() + " exec " + std::string(VOCA_BINARY_DIR) + "/bin/voca " +
                              args + " > " + log.string() + " 2>&1";
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = 0;
  REQUIRE(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char* const*>(argv), environ) == 0);
  return pid;
}

// Sends `signal` to the process once `path` exists with more than min_bytes: the process is held
// (SIGSTOP) the moment the file is seen and gets the signal before it goes on, so the signal lands
// at that point of its work however loaded the machine is. False when the file did not appear
// within a minute.
inline bool signalWhenWritten(pid_t pid, const std::filesystem::path& path, int signal, std::uintmax_t min_bytes = 0) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  std::error_code ec;
  const auto written = [&] {
    return std::filesystem::exists(path, ec) && std::filesystem::file_size(path, ec) > min_bytes;
  };
  while (!written() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  kill(pid, SIGSTOP);
  const bool seen = written();
  kill(pid, signal);
  kill(pid, SIGCONT);
  return seen;
}

// Waits for a process started by spawnVoca; its exit code, or -1 when a signal killed it.
inline int waitExitCode(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A fresh folder under the build tree, removed when the test ends.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) {
    std::random_device seed;
    path_ = std::filesystem::path(VOCA_BINARY_DIR) / "test-scratch" / (name + "-" + std::to_string(seed()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Writes a text file, creating its folder; the test stops if the file cannot be written.
inline void writeText(const std::filesystem::path& path, const std::string& text) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  REQUIRE_MESSAGE(out.good(), "cannot write " << path.string());
}

// The message of the voca::InputError that f() throws, or "(no error)" when it returns normally.
template <typename F>
std::string inputErrorOf(F&& f) {
  try {
    f();
  } catch (const voca::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Checks that an error message contains the expected part, showing the whole message on failure.
inline void expectError(const std::string& error, const std::string& part) {
  INFO("message: " << error);
  INFO("expected part: " << part);
  CHECK(error.find(part) != std::string::npos);
}

}  // namespace voca::test
