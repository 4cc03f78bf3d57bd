#pragma once
// `voca synth`: renders a synthetic stereo sequence with exact ground truth and writes it as a EuRoC
// folder (mav0/cam0, mav0/cam1, mav0/state_groundtruth_estimate0/data.csv) plus the rig as Basalt
// JSON (<out>/calib.json). The camera follows a motion preset or a trajectory file; the room, its
// objects and the sensor noise come from seeds, so the same options give the same bytes.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "voca/synth/motion.h"

namespace voca::pipeline {

struct SynthOptions {
  std::filesystem::path out;
  std::string camera = "euroc";  // euroc, tumvi or a calibration file/folder
  std::filesystem::path trajectory;
  std::string motion = "gentle";
  std::optional<double> seconds;
  double start_s = 0.0;  // skip this much of a trajectory file (take-off, standing still)
  double rate_hz = 20.0;
  std::uint64_t seed = 1;
  std::uint32_t scene_seed = 7;
  double noise_sigma = 2.0;
  double psf_sigma_px = 0.0;
  int supersample = 3;
  int threads = 2;
  double exposure_ms = 0.0;  // shutter open time centred on each timestamp; 0 = instantaneous
  double gain = 1.0;         // sensor gain on the scene's irradiance; < 1 = dark, low contrast
  bool progress = true;      // the plan and progress lines on stderr
  // Asked before each frame; true stops the run early. The frames rendered so far are written as a
  // complete, shorter sequence (images, ground truth, calibration).
  std::function<bool()> stop_requested;
};

struct SynthResult {
  int frames = 0;                        // stereo frames written
  int planned_frames = 0;                // stereo frames the options asked for
  bool stopped = false;                  // stop_requested() ended the run after `frames` frames
  double seconds = 0.0;                  // wall time of the whole run
  synth::ImageMotionStats motion;        // true optical flow of cam0 between frames (coarse grid)
  std::optional<double> blur_median_px;  // cam0 motion-blur streak per frame (with an exposure only)
  std::optional<double> blur_max_px;
  std::vector<std::string> warnings;  // e.g. a trajectory file shorter than --seconds
};

// Validates the options (InputError naming the option), renders every frame with `threads`
// workers and writes the folder. Progress goes to stderr when options.progress is set. When
// options.stop_requested turns true it ends there, writes the frames so far as the sequence and sets
// stopped.
SynthResult synthesizeSequence(const SynthOptions& options);

}  // namespace voca::pipeline
