#pragma once
// What a run did, for people: the summaries `voca run` and `voca track` print, and why a run that
// estimated nothing failed.

#include <cstdio>
#include <string>

#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

// Frames, keyframes, resets, ms per frame, frames/s, skipped frames, source losses, ATE/RTE.
std::string formatRunSummary(const VoRunResult& result);
void printRunSummary(const VoRunResult& result, std::FILE* out);

// The frontend's: tracks, survival, rescues by the prior, guess distances, detections, time.
std::string formatTrackSummary(const VoRunResult& result, const FrontendConfig& config);
void printTrackSummary(const VoRunResult& result, const FrontendConfig& config, std::FILE* out);

// VoRunResult::failure for a run whose every frame was lost, with the likeliest cause: a tracker
// capacity or images too small for the detection grid to give a frame the points the estimator
// needs, else calibration or config (the per-frame messages name each frame's reason).
std::string noEstimateReason(const VoRunResult& result, int max_points);

}  // namespace voca::pipeline
