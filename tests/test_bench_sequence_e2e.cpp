// The benchmarks' default moving sequence (pipeline/harness/bench_sequence.h): cache location and
// naming, bad specs, a stopped generation, and one real generation (a short one: 1 s of video),
// reused on the second call.

#include <doctest/doctest.h>

#include <cstdlib>
#include <optional>
#include <string>

#include "formats/dataset/dataset.h"
#include "pipeline/harness/bench_sequence.h"
#include "tests/test_support.h"

namespace fs = std::filesystem;
using voca::harness::BenchSequenceSpec;

namespace {

// Sets an environment variable for one scope and restores it afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value != nullptr) {
      ::setenv(name, value, 1);
    } else {
      ::unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

}  // namespace

TEST_CASE("bench sequence: cache root from XDG_CACHE_HOME, else HOME/.cache; named by camera, motion, length, rate") {
  {
    ScopedEnv xdg("XDG_CACHE_HOME", "/x/cache");
    CHECK(voca::harness::benchCacheRoot() == fs::path("/x/cache/voca"));
  }
  {
    ScopedEnv xdg("XDG_CACHE_HOME", "");
    ScopedEnv home("HOME", "/home/u");
    CHECK(voca::harness::benchCacheRoot() == fs::path("/home/u/.cache/voca"));
    ScopedEnv no_home("HOME", nullptr);
    CHECK(voca::test::inputErrorOf([] { voca::harness::benchCacheRoot(); }).find("XDG_CACHE_HOME") !=
          std::string::npos);
  }
  BenchSequenceSpec spec;
  CHECK(voca::harness::benchSequenceFolder(spec, "/c") == fs::path("/c/bench/euroc-aggressive-40s-500k"));
  CHECK(voca::harness::benchSequenceConfig(spec) == "euroc");
  CHECK(voca::harness::describeBenchSequence(spec).find("752x480") != std::string::npos);
  spec.camera = "tumvi";
  spec.bitrate_bps = 2'000'000;
  CHECK(voca::harness::benchSequenceFolder(spec, "/c") == fs::path("/c/bench/tumvi-aggressive-40s-2000k"));
  CHECK(voca::harness::describeBenchSequence(spec).find("512x512") != std::string::npos);

  spec.camera = "nope";
  const std::string error =
      voca::test::inputErrorOf([&] { voca::harness::ensureBenchSequence(spec, "/nonexistent", false, {}); });
  CHECK(error.find("unknown camera 'nope'") != std::string::npos);
}

TEST_CASE("bench sequence: rendered and encoded once, then reused; a stop leaves no folder") {
  voca::test::ScratchDir dir("bench-sequence");
  BenchSequenceSpec spec;
  spec.seconds = 1;
  // Stopped before the first frame: nothing is cached, so the next call starts over.
  int asked = 0;
  CHECK_FALSE(voca::harness::ensureBenchSequence(spec, dir.path(), false, [&] { return ++asked > 0; }));
  CHECK(asked >= 1);
  CHECK_FALSE(fs::exists(voca::harness::benchSequenceFolder(spec, dir.path())));

  const std::optional<fs::path> video = voca::harness::ensureBenchSequence(spec, dir.path(), false, {});
  REQUIRE(video);
  CHECK(*video == voca::harness::benchSequenceFolder(spec, dir.path()));
  const voca::Dataset dataset = voca::openDataset(*video);
  CHECK(dataset.layout == voca::DatasetLayout::kVocaVideo);
  CHECK(dataset.frames.size() == 20);  // 1 s at 20 Hz
  CHECK(dataset.ground_truth.has_value());
  // Only the finished video stays: no partial folders, no rendering.
  int entries = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir / "bench")) {
    CHECK(entry.path() == *video);
    ++entries;
  }
  CHECK(entries == 1);
  // The second call finds it without rendering again: the video is not rewritten.
  const auto written = fs::last_write_time(dataset.video_left);
  CHECK(voca::harness::ensureBenchSequence(spec, dir.path(), false, [] { return true; }) == video);
  CHECK(fs::last_write_time(dataset.video_left) == written);
}
