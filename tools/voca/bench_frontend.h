#pragma once
// Shared by `voca track` and `voca bench frontend`: a stereo sequence loaded into memory (images,
// motion fields, picture types) from a raw dataset or a VOCA video folder, and the bench mode.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/voca/command.h"
#include "voca/calib/calibration.h"
#include "voca/core/image.h"
#include "voca/motion/motion_field.h"

namespace voca::cli {

// One stereo frame in memory.
struct LoadedStereoFrame {
  std::int64_t t_ns = 0;
  GrayImage left, right;
  MotionField motion_left, motion_right;  // no vectors for raw images
  PictureType type = PictureType::kUnknown;
};

struct LoadedSequence {
  std::vector<LoadedStereoFrame> frames;
  StereoRig rig;
  bool has_motion = false;  // decoded from video
  std::string description;
};

// How to load: calibration override, frame limit (0 = all), and for raw datasets an optional
// encode/decode round trip at `encode_bitrate_bps` (libx264, the paper's settings) so that the
// frames carry codec artefacts and motion vectors.
struct LoadOptions {
  std::optional<std::filesystem::path> calibration;
  int max_frames = 0;
  std::int64_t encode_bitrate_bps = 0;  // 0 = use raw images as they are
};

// Throws InputError for unknown datasets, missing calibration, or images that do not match it.
LoadedSequence loadStereoSequence(const std::filesystem::path& input, const LoadOptions& options);

// `voca bench frontend`: declares the options and returns the runner.
Runner configureFrontendBench(CLI::App& app);

}  // namespace voca::cli
