#pragma once
// A VOCA video folder decoded back into a EuRoC folder (mav0/camN/data/<t_ns>.png + data.csv, with the
// ground truth and calib.json beside): exactly the pixels a VOCA-RT run on the video sees, so another
// system (Basalt, ORB-SLAM3 ...) can be evaluated on the same degraded input.

#include <cstdint>
#include <filesystem>
#include <functional>

namespace voca::decode {

struct DecodedDatasetReport {
  std::int64_t frames = 0;
  int width = 0, height = 0;
  bool ground_truth_copied = false;
  bool calibration_copied = false;
};

// Called after each stereo frame: frames written, frames in all.
using DecodedDatasetProgress = std::function<void(std::int64_t done, std::int64_t total)>;

// Decodes every frame of both cameras with the software decoder (the pixels do not depend on the
// decoder). Throws InputError when the folder is not a VOCA video folder or a frame cannot be
// decoded, naming it; RuntimeFailure when out cannot be written.
DecodedDatasetReport writeDecodedEuroc(const std::filesystem::path& video_folder, const std::filesystem::path& out,
                                       const DecodedDatasetProgress& progress = {});

}  // namespace voca::decode
