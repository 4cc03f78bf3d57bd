#include "pipeline/harness/bench_sequence.h"

#include <fmt/core.h>

#include <cstdlib>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "pipeline/synth/synth_runner.h"
#include "pipeline/vo/vo_runner.h"
#include "voca/core/error.h"
#include "voca/synth/rigs.h"

namespace voca::harness {

namespace fs = std::filesystem;

namespace {

constexpr double kRateHz = 20.0;  // `voca synth`'s default rate, given explicitly so the name stays true

void checkSpec(const BenchSequenceSpec& spec) {
  if (!synth::builtinRig(spec.camera)) {
    throw InputError(fmt::format("benchmark sequence: unknown camera '{}' (expected euroc or tumvi)", spec.camera));
  }
  if (spec.seconds < 1) throw InputError(fmt::format("benchmark sequence: {} s is too short", spec.seconds));
  if (spec.bitrate_bps <= 0) throw InputError("benchmark sequence: the bitrate must be positive");
  if (spec.supersample < 1 || spec.supersample > 8) {
    throw InputError(fmt::format("benchmark sequence: supersample {} is outside 1..8", spec.supersample));
  }
  if (spec.keyframe_interval < 0) {
    throw InputError(fmt::format("benchmark sequence: keyframe interval {} is negative", spec.keyframe_interval));
  }
}

// Renders the sequence into raw (a fresh folder) in this process, with `voca synth`'s defaults
// otherwise. False when stopped.
bool render(const BenchSequenceSpec& spec, const fs::path& raw, bool progress,
            const std::function<bool()>& stop_requested) {
  pipeline::SynthOptions options;
  options.out = raw;
  options.camera = spec.camera;
  options.motion = spec.motion;
  options.seconds = spec.seconds;
  options.rate_hz = kRateHz;
  options.supersample = spec.supersample;
  options.progress = progress;
  options.stop_requested = stop_requested;
  return !pipeline::synthesizeSequence(options).stopped;
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
  const BenchSequenceSpec defaults;
  std::string name =
      fmt::format("{}-{}-{}s-{}", spec.camera, spec.motion, spec.seconds, encode::bitrateLabel(spec.bitrate_bps));
  if (spec.supersample != defaults.supersample) name += fmt::format("-ss{}", spec.supersample);
  if (spec.keyframe_interval != defaults.keyframe_interval) name += fmt::format("-gop{}", spec.keyframe_interval);
  return root / "bench" / name;
}

std::string benchSequenceConfig(const BenchSequenceSpec& spec) { return spec.camera; }

std::string describeBenchSequence(const BenchSequenceSpec& spec) {
  checkSpec(spec);
  const StereoRig rig = *synth::builtinRig(spec.camera);
  return fmt::format("moving {} sequence ({}x{} synthetic, {} motion, {} s, {}bit/s)", spec.camera,
                     rig.cameras[0].width, rig.cameras[0].height, spec.motion, spec.seconds,
                     encode::bitrateLabel(spec.bitrate_bps));
}

std::optional<fs::path> ensureBenchSequence(const BenchSequenceSpec& spec, const fs::path& root, bool progress,
                                            const std::function<bool()>& stop_requested) {
  checkSpec(spec);
  const fs::path video = benchSequenceFolder(spec, root);
  if (fs::is_directory(video)) return video;
  const fs::path partial = video.string() + ".partial";
  fs::remove_all(partial);
  fs::create_directories(video.parent_path());
  if (progress) {
    fmt::print(stderr, "generating the {} once (cached in {}); this takes minutes\n", describeBenchSequence(spec),
               video.string());
  }
  if (!generateBenchSequence(spec, partial, progress, stop_requested)) return std::nullopt;
  fs::rename(partial, video);
  return video;
}

bool generateBenchSequence(const BenchSequenceSpec& spec, const fs::path& video, bool progress,
                           const std::function<bool()>& stop_requested) {
  checkSpec(spec);
  const fs::path raw = video.string() + ".raw.partial";
  fs::remove_all(raw);
  const bool done = render(spec, raw, progress, stop_requested) &&
                    encode::encodeForReplay(raw, video, spec.bitrate_bps, std::nullopt, progress, stop_requested,
                                            spec.keyframe_interval);
  // The encoding keeps the ground truth; the rendering (hundreds of MB of PNG) is not needed again.
  fs::remove_all(raw);
  return done;
}

}  // namespace voca::harness
