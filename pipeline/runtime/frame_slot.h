#pragma once
// One frame's place in the pipeline: every message it becomes on its way (DESIGN.md section 2) and
// the timestamps of every stage it passed. Slots are allocated once, in a pool, when the pipeline is
// built; a frame moves from stage to stage as a pointer to its slot, and whoever holds the pointer
// owns the slot.

#include <array>
#include <cstdint>
#include <vector>

#include "drivers/source/stereo_source.h"
#include "platform/realtime/clock.h"
#include "voca/backend/pose_estimate.h"
#include "voca/core/stereo_frame.h"
#include "voca/core/tracked_frame.h"
#include "voca/frontend/frontend_stats.h"

namespace voca::pipeline {

// The most stages a pipeline has: source, encode, decode, frontend, backend, sink.
inline constexpr int kMaxStages = 8;

// When one stage worked on a frame: monotonic clock (platform::monotonicNs), and the CPU time its
// thread spent.
struct StageTiming {
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
  std::int64_t cpu_ns = 0;
  std::int64_t cpu_start_ns = 0;
  double serviceMs() const { return platform::nsToMs(end_ns - start_ns); }
};

struct FrameSlot {
  int pool_index = 0;
  int owner_stage = -1;         // the stage working on it (the runner's bookkeeping)
  std::int64_t sequence = 0;    // order in which the source produced the frame, from 0
  std::int64_t arrival_ns = 0;  // monotonic time the frame became available (captured, received or read)
  std::array<StageTiming, kMaxStages> timing{};
  // The helper thread's run for this frame (Stage::helper), of stage helper_stage; -1: none ran.
  StageTiming helper_timing{};
  int helper_stage = -1;

  RawStereoFrame raw;           // raw sources; the encode stage's input
  EncodedStereoPacket encoded;  // video sources; the encode stage's output, the decode stage's input
  DecodedStereoFrame frame;     // the frontend's input
  TrackedStereoFrame tracked;   // the frontend's output, the backend's input
  FrontendStats frontend_stats;
  std::vector<PointTrace> left_traces;  // the left camera's temporal step, kept for overlays
  PoseEstimate pose;                    // the backend's output
  // The estimator's window landmarks in the world frame after this frame, filled by the backend stage
  // only when a sink reads them (FrameSinkNeeds::landmarks); capacity fixed by reserve().
  std::vector<Eigen::Vector3f> landmarks_world;
  // Frames the pipeline dropped (live policy) and skipped as damaged since the start, as of this
  // frame reaching the last stage (the sinks).
  std::int64_t dropped_so_far = 0;
  std::int64_t damaged_so_far = 0;

  // Source frame index of the frame (stamped by the source).
  std::int64_t frameIndex() const { return frame.frame_index; }

  // Sizes every buffer for frames up to width x height, max_points points per camera and
  // max_landmarks window landmarks (0: landmarks are not copied).
  void reserve(int width, int height, int max_points, int max_landmarks = 0);
};

}  // namespace voca::pipeline
