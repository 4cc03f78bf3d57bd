#pragma once
// `voca bench backend`: the sliding-window estimator's cost per stereo frame, timed alone on this
// thread's CPU clock. The input is either the frontend's real tracks on a sequence (recorded once
// by a frontend-only run, so the estimator is fed exactly what the pipeline feeds it) or synthetic
// observations of a room.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/vo/vo_runner.h"
#include "voca/backend/backend_config.h"
#include "voca/calib/calibration.h"
#include "voca/core/tracked_frame.h"

namespace voca::pipeline {

struct TrackRecording {
  std::vector<TrackedStereoFrame> frames;  // every frame's tracks, in order
  StereoRig rig;
  VocaConfig config;  // as the frontend ran it (its backend section is what the estimator gets)
  std::string description;
};

// Runs the frontend alone over options.input (estimate is forced off; decoding and tracking as in
// `voca run`) and keeps a copy of every frame's tracks. Throws InputError for bad input and
// RuntimeFailure when a stage fails; nullopt when stop_requested ended the run early.
std::optional<TrackRecording> recordFrontendTracks(VoRunOptions options);

struct EstimatorTiming {
  // Per measured frame, thread CPU time of process(): the median over the runs (perFrameMedian).
  std::vector<double> cpu_ms;
  std::vector<double> run_median_ms;  // each run's own median over the frames, in run order
  std::size_t warmup = 0;             // frames before the first measured one (the window filling)
  int measured = 0;
  int resets = 0;     // over all frames, warm-up included
  int keyframes = 0;  // measured frames that became keyframes
  double mean_window_keyframes = 0.0, mean_left_points = 0.0, mean_inliers = 0.0;
  // LM iterations of the window optimisation per measured frame: the time's main factor, and free of
  // the noise a shared machine puts on the clock.
  double mean_lm_iterations = 0.0, mean_linearizations = 0.0, mean_cost_passes = 0.0, mean_pose_iterations = 0.0;
};

// Feeds the frames to a new estimator in order and times each process() call; frames before
// `warmup` (the window filling up) are run but not measured. Does so `repeat` times, each with a new
// estimator. Throws InputError when there are not more frames than warmup or repeat < 1, and
// RuntimeFailure when a run does not repeat the first one's estimates (the timing would compare
// different work).
EstimatorTiming timeEstimator(const std::vector<TrackedStereoFrame>& frames, const StereoRig& rig,
                              const BackendConfig& config, std::size_t warmup, int repeat = 1);

}  // namespace voca::pipeline
