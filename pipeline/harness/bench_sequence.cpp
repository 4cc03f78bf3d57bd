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

std::optional<fs::path> ensureBenchSequence(const BenchSequenceSpec& spec, const fs::path& root, bool progress,
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
  if (!render(spec, raw, progress, stop_requested)) return std::nullopt;
  if (!encode::encodeForReplay(raw, partial, spec.bitrate_bps, std::nullopt, progress, stop_requested)) {
    return std::nullopt;
  }
  // The encoding keeps the ground truth; the rendering (hundreds of MB of PNG) is not needed again.
  fs::rename(partial, video);
  fs::remove_all(raw);
  return video;
}

}  // namespace voca::harness
