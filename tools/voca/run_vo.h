#pragma once
// The whole single-threaded VO run behind `voca run` and `voca demo`: frames from a raw dataset or a
// VOCA video folder (optionally encoded on the fly), KLT frontend, sliding-window backend, the
// causal trajectory, timings and, when the dataset has ground truth, ATE/RTE.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "voca/eval/evaluate.h"
#include "voca/frontend/frontend_config.h"
#include "voca/trajectory/trajectory.h"

namespace voca::cli {

// What to run.
struct VoRunOptions {
  std::filesystem::path input;
  std::optional<std::filesystem::path> calibration;
  std::optional<std::filesystem::path> config;
  std::optional<std::filesystem::path> ground_truth;  // overrides the dataset's own
  std::optional<PriorMode> mode;                      // overrides the config's frontend.prior_mode
  std::int64_t encode_bitrate_bps = 0;                // raw datasets: encode to a temporary VOCA folder first
  int max_frames = 0;                                 // 0 = all
  int max_points = 1000;                              // frontend capacity per camera
  bool progress = true;                               // progress lines on stderr
};

// What came out.
struct VoRunResult {
  std::string description;
  PriorMode mode = PriorMode::kNone;
  bool has_motion = false;  // decoded video (motion vectors available)
  Trajectory trajectory;    // causal, body frame of the calibration
  int frames = 0, keyframes = 0, resets = 0, lost = 0;
  std::vector<double> frontend_ms, backend_ms;
  std::optional<EvalReport> eval;  // when the dataset has ground truth
  std::string ground_truth;
};

VoRunResult runVisualOdometry(const VoRunOptions& options);

// The end-of-run summary (frames, keyframes, resets, ms per frame, ATE/RTE).
void printRunSummary(const VoRunResult& result);

double medianOf(std::vector<double> values);
double quantileOf(std::vector<double> values, double q);

}  // namespace voca::cli
