#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>
#include <vector>

#include "platform/filesystem/output_paths.h"
#include "platform/process/child_process.h"
#include "platform/realtime/clock.h"
#include "tests/test_support.h"
#include "voca/core/quantile.h"

TEST_CASE("quantile of an empty sample is NaN, not a plausible number") {
  CHECK(std::isnan(voca::quantile({}, 0.5)));
  CHECK(std::isnan(voca::median({})));
}

TEST_CASE("quantile known answers: linear interpolation between closest ranks") {
  // numpy.quantile([3, 1, 4, 1, 5], q) for q = 0, 0.25, 0.5, 0.9, 1 gives 1, 1, 3, 4.6, 5.
  const std::vector<double> odd{3, 1, 4, 1, 5};
  CHECK(voca::quantile(odd, 0.0) == 1.0);
  CHECK(voca::quantile(odd, 0.25) == 1.0);
  CHECK(voca::quantile(odd, 0.5) == 3.0);
  CHECK(voca::quantile(odd, 0.9) == doctest::Approx(4.6).epsilon(1e-12));
  CHECK(voca::quantile(odd, 1.0) == 5.0);
  // Even count: the median is the mean of the middle two, exactly (as voca eval has always printed).
  CHECK(voca::median({10, 2, 7, 1}) == 4.5);
  CHECK(voca::median({0.1, 0.7}) == 0.5 * (0.1 + 0.7));
  // numpy.quantile([1, 2, 7, 10], 0.99) = 7 + 2.97 * 3 ... = 9.91.
  CHECK(voca::quantile({10, 2, 7, 1}, 0.99) == doctest::Approx(9.91).epsilon(1e-12));
  CHECK(voca::median({42}) == 42.0);
  CHECK(voca::quantile({42}, 0.99) == 42.0);
}

TEST_CASE("quantile keeps the caller's order; quantileInPlace works on a span") {
  const std::vector<double> values{5, 4, 3, 2, 1};
  CHECK(voca::median(values) == 3.0);
  CHECK(values == std::vector<double>{5, 4, 3, 2, 1});
  std::vector<double> scratch{9, 8, 7, 6};
  CHECK(voca::quantileInPlace(scratch, 1.0 / 3.0) == doctest::Approx(7.0).epsilon(1e-12));
}

TEST_CASE("quantile rejects q outside [0, 1]") {
  CHECK_THROWS_AS(voca::quantile({1, 2}, -0.1), std::domain_error);
  CHECK_THROWS_AS(voca::quantile({1, 2}, 1.5), std::domain_error);
  CHECK_THROWS_AS(voca::quantile({1, 2}, std::nan("")), std::domain_error);
}

TEST_CASE("thread CPU clock counts this thread's work, not its sleep") {
  const std::int64_t sleep_start = voca::platform::threadCpuNs();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::int64_t slept_ns = voca::platform::threadCpuNs() - sleep_start;
  // Sleeping costs next to no CPU; 10 ms leaves room for a slow emulator's syscall overhead.
  CHECK(slept_ns < 10'000'000);

  const std::int64_t busy_start = voca::platform::threadCpuNs();
  const std::int64_t wall_start = voca::platform::monotonicNs();
  volatile double sink = 0.0;
  while (voca::platform::monotonicNs() - wall_start < 20'000'000) sink = sink + 1.0;
  const std::int64_t busy_ns = voca::platform::threadCpuNs() - busy_start;
  // 20 ms of wall time spinning: at least some CPU time (> 1 ms even on a busy, shared machine) and
  // never more than the wall time it took (plus clock granularity).
  CHECK(busy_ns > 1'000'000);
  CHECK(busy_ns <= voca::platform::monotonicNs() - wall_start + 1'000'000);
}

TEST_CASE("runForked reports the copy's exit code, its stderr and a crash, and this process goes on") {
  int touched = 0;
  const voca::platform::ForkedRun fine = voca::platform::runForked([&] {
    touched = 1;  // the copy's memory, not this process's
    std::fprintf(stderr, "[codec @ 0x1] a reason\n");
    return 3;
  });
  CHECK(fine.exit.signal == 0);
  CHECK(fine.exit.exit_code == 3);
  CHECK(!fine.exit.succeeded());
  CHECK(fine.output == "[codec @ 0x1] a reason\n");
  CHECK(touched == 0);

  CHECK(voca::platform::runForked([] { return 0; }).exit.succeeded());
  CHECK(voca::platform::runForked([]() -> int { throw std::runtime_error("x"); }).exit.exit_code == 1);

  const voca::platform::ForkedRun crash = voca::platform::runForked([] {
    std::signal(SIGABRT, SIG_DFL);
    std::abort();
    return 0;
  });
  CHECK(crash.exit.signal == SIGABRT);
  CHECK(voca::platform::describeExit(crash.exit).find("signal") != std::string::npos);
}

TEST_CASE("isWithin compares whole path elements of resolved paths; requireOutputsApart names both paths") {
  CHECK(voca::isWithin("a/b/c.txt", "a/b"));
  CHECK(voca::isWithin("a/b", "a/b/"));
  CHECK(voca::isWithin("a/./x/../b", "a/b"));
  CHECK(voca::isWithin(std::filesystem::current_path() / "a" / "b", "a"));  // absolute against relative
  CHECK_FALSE(voca::isWithin("ab/c", "a"));                                 // a string prefix is not a parent folder
  CHECK_FALSE(voca::isWithin("a", "a/b"));
  const voca::NamedPath inputs[] = {{"the ground truth", "data/gt.csv"}, {"the dataset's mav0 folder", "seq/mav0"}};
  const voca::NamedPath apart[] = {{"-o", "out/t.txt"}, {"--stats", "out/s.json"}, {"--trace", ""}};
  CHECK_NOTHROW(voca::requireOutputsApart(apart, inputs));
  const voca::NamedPath onto_input[] = {{"--stats", "./data/gt.csv"}};
  CHECK(voca::test::inputErrorOf([&] { voca::requireOutputsApart(onto_input, inputs); }) ==
        "--stats ./data/gt.csv is the ground truth (data/gt.csv), which this command reads; choose another path");
  const voca::NamedPath twice[] = {{"-o", "out/t.txt"}, {"--trace", "out/../out/t.txt"}};
  CHECK(voca::test::inputErrorOf([&] { voca::requireOutputsApart(twice, inputs); }) ==
        "-o and --trace name the same file out/../out/t.txt; give each its own");
  CHECK_NOTHROW(voca::requireWritableFile({"-o", std::filesystem::temp_directory_path() / "voca-new-file.txt"}));
  CHECK_FALSE(std::filesystem::exists(std::filesystem::temp_directory_path() / "voca-new-file.txt"));  // not created
  CHECK(voca::test::inputErrorOf([&] {
          voca::requireWritableFile({"-o", "no-such-folder/t.txt"});
        }) == "cannot write -o no-such-folder/t.txt: the folder no-such-folder does not exist");
  CHECK(voca::test::inputErrorOf([&] { voca::requireNotDevice("/dev/zero", "trace file"); }) ==
        "trace file /dev/zero is a device, not a file");
  CHECK_NOTHROW(voca::requireNotDevice("/proc/self/status", "trace file"));
  CHECK_NOTHROW(voca::requireFoldersApart({"the output folder", "seq/mav0/enc"}, {"the input dataset", "seq"}));
  CHECK(voca::test::inputErrorOf([&] {
          voca::requireFoldersApart({"the output folder", "seq"}, {"the input dataset", "seq/mav0"});
        }) == "the output folder seq holds the input dataset (seq/mav0); choose a folder apart from it");
}
