#include "pipeline/harness/bench_sequence.h"

#include <fmt/core.h>

#include <chrono>
#include <cstdlib>
#include <system_error>
#include <thread>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "pipeline/vo/vo_runner.h"
#include "platform/process/child_process.h"
#include "voca/core/error.h"
#include "voca/synth/rigs.h"

namespace voca::harness {

namespace fs = std::filesystem;

namespace {

constexpr int kRateHz = 20;  // `voca synth`'s default rate, given explicitly so the frame count is known

void checkSpec(const BenchSequenceSpec& spec) {
  if (!synth::builtinRig(spec.camera)) {
    throw InputError(fmt::format("benchmark sequence: unknown camera '{}' (expected euroc or tumvi)", spec.camera));
  }
  if (spec.seconds < 1) throw InputError(fmt::format("benchmark sequence: {} s is too short", spec.seconds));
  if (spec.bitrate_bps <= 0) throw InputError("benchmark sequence: the bitrate must be positive");
}

std::size_t countFiles(const fs::path& folder) {
  std::error_code error;
  std::size_t count = 0;
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) ++count;
  return count;
}

// `voca synth` into raw (a fresh folder), reporting the frames written while it runs. False when
// stopped (the child is left to the stop signal, which reaches the whole process group).
bool render(const BenchSequenceSpec& spec, const fs::path& raw, const fs::path& log, const fs::path& voca_executable,
            bool progress, const std::function<bool()>& stop_requested) {
  const std::vector<std::string> argv = {voca_executable.string(),
                                         "synth",
                                         "--camera",
                                         spec.camera,
                                         "--motion",
                                         spec.motion,
                                         "--seconds",
                                         std::to_string(spec.seconds),
                                         "--rate",
                                         std::to_string(kRateHz),
                                         "--out",
                                         raw.string()};
  fs::create_directories(log.parent_path());
  fs::remove(log);
  const pid_t pid = platform::startChild(argv, log);
  const int frames = spec.seconds * kRateHz;
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    if (const std::optional<platform::ChildExit> exit = platform::pollChild(pid)) {
      if (progress) fmt::print(stderr, "\n");
      if (stop_requested && stop_requested()) return false;
      if (!exit->succeeded()) {
        throw RuntimeFailure(fmt::format("rendering the benchmark sequence failed ({}); see {}",
                                         platform::describeExit(*exit), log.string()));
      }
      return true;
    }
    if (progress) {
      const auto done = static_cast<int>(countFiles(raw / "mav0" / "cam1" / "data"));
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      fmt::print(stderr, "\rrendering: frame {}/{}, {:.0f} s elapsed", done, frames, elapsed);
      if (done > 0) fmt::print(stderr, ", about {:.0f} s left", elapsed / done * (frames - done));
      fmt::print(stderr, "   ");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
}

}  // namespace

fs::path benchCacheRoot() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && *xdg != '\0') return fs::path(xdg) / "voca";
  const char* home = std::getenv("HOME");
  if (home != nullptr && *home != '\0') return fs::path(home) / ".cache" / "voca";
  throw InputError("no cache folder for the benchmark sequence: set XDG_CACHE_HOME or HOME, or give an input");
}

fs::path benchSequenceFolder(const BenchSequenceSpec& spec, const fs::path& root) {
  return root / "bench" /
         fmt::format("{}-{}-{}s-{}", spec.camera, spec.motion, spec.seconds, encode::bitrateLabel(spec.bitrate_bps));
}

std::string benchSequenceConfig(const BenchSequenceSpec& spec) { return spec.camera; }

std::string describeBenchSequence(const BenchSequenceSpec& spec) {
  checkSpec(spec);
  const StereoRig rig = *synth::builtinRig(spec.camera);
  return fmt::format("moving {} sequence ({}x{} synthetic, {} motion, {} s, {}bit/s)", spec.camera,
                     rig.cameras[0].width, rig.cameras[0].height, spec.motion, spec.seconds,
                     encode::bitrateLabel(spec.bitrate_bps));
}

std::optional<fs::path> ensureBenchSequence(const BenchSequenceSpec& spec, const fs::path& root,
                                            const fs::path& voca_executable, bool progress,
                                            const std::function<bool()>& stop_requested) {
  checkSpec(spec);
  const fs::path video = benchSequenceFolder(spec, root);
  if (fs::is_directory(video)) return video;
  const fs::path raw = video.string() + ".raw.partial";
  const fs::path partial = video.string() + ".partial";
  fs::remove_all(raw);
  fs::remove_all(partial);
  fs::create_directories(video.parent_path());
  if (progress) {
    fmt::print(stderr, "generating the {} once (cached in {}); this takes minutes\n", describeBenchSequence(spec),
               video.string());
  }
  const fs::path log = root / "bench" / "logs" / (video.filename().string() + "-synth.txt");
  if (!render(spec, raw, log, voca_executable, progress, stop_requested)) return std::nullopt;
  if (!pipeline::encodeForReplay(raw, partial, spec.bitrate_bps, std::nullopt, progress, stop_requested)) {
    return std::nullopt;
  }
  // The encoding keeps the ground truth; the rendering (hundreds of MB of PNG) is not needed again.
  fs::rename(partial, video);
  fs::remove_all(raw);
  return video;
}

}  // namespace voca::harness
