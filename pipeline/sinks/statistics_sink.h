#pragma once
// What the frontend and backend did over a run: totals (tracks, survival, prior rescues, consensus
// rejections, detections, keyframes, resets), the distance from each initial guess to the converged
// position (the paper's Fig. 5) as histograms, and one row per frame. Fixed memory: rows are kept up
// to the capacity given at construction, everything else is counted without limit.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/sinks/sink_stage.h"

namespace voca::pipeline {

// Distances in pixels in fixed bins (0.01 px up to 16 px, then one overflow bin).
class DistanceHistogram {
 public:
  static constexpr double kBinPx = 0.01;
  static constexpr int kBins = 1600;
  static constexpr double kRangePx = kBinPx * kBins;  // the overflow bin holds what lies beyond
  void record(double px);
  std::int64_t count() const { return count_; }
  // Midpoint of the bin holding the sample of rank round(q * (count - 1)); 0 when empty; infinity
  // when that sample lies beyond kRangePx (fast motion: the previous position is often that far off).
  double quantile(double q) const;
  // quantile(q) for people: "1.234", or "> 16" beyond the range.
  std::string formatQuantile(double q) const;
  // Counts per bin, the overflow bin last.
  const std::array<std::int64_t, kBins + 1>& bins() const { return bins_; }

 private:
  std::array<std::int64_t, kBins + 1> bins_{};
  std::int64_t count_ = 0;
};

// One frame as the statistics file lists it.
struct FrameRecord {
  std::int64_t frame_index = 0;
  std::int64_t t_ns = 0;
  int missing_before = 0;  // source frames dropped or damaged just before this one
  char picture_type = '?';
  bool bridged = false;
  int left = 0, right = 0;  // observations output
  int kept = 0, lost = 0, rescued = 0, consensus_rejections = 0, detected = 0;
  // Backend (zero when the run has no backend).
  std::uint8_t state = 0;  // TrackingState
  bool keyframe = false;
  int landmarks = 0;
  int inliers = 0;
  // Stage times: service (wall) and thread CPU, milliseconds.
  float decode_ms = 0.f, frontend_ms = 0.f, backend_ms = 0.f;
  float frontend_cpu_ms = 0.f, backend_cpu_ms = 0.f;
};

struct FrontendTotals {
  std::int64_t previous = 0, kept = 0, rescued = 0, consensus = 0, tracked_plain = 0, tracked_prior = 0,
               with_vector = 0, distrusted = 0, prior_confirmed = 0, flow_retried = 0, flow_searched = 0;
  std::int64_t detected = 0, detected_right_only = 0, stereo_matched = 0, stereo_rematched = 0, epipolar = 0,
               thinned = 0;
  std::int64_t bridged_frames = 0;
  std::int64_t left_points = 0, right_points = 0;
  int min_left = 0, max_left = 0;
  DistanceHistogram guess_plain, guess_prior;  // previous position / MV prior -> converged
};

struct BackendTotals {
  std::int64_t keyframes = 0, resets = 0, lost = 0;
};

class StatisticsSink final : public FrameSink {
 public:
  // row_capacity: frames whose rows are kept (the expected frame count; rows beyond it are counted
  // only). stage_positions: where decode, frontend and backend sit in the pipeline (-1 when absent),
  // to read their times from the slot.
  StatisticsSink(std::size_t row_capacity, int decode_stage, int frontend_stage, int backend_stage);
  void consume(const FrameSlot& slot) override;

  std::int64_t frames() const { return frames_; }
  const FrontendTotals& frontend() const { return frontend_; }
  const BackendTotals& backend() const { return backend_; }
  const std::vector<FrameRecord>& rows() const { return rows_; }
  bool rowsTruncated() const { return frames_ > static_cast<std::int64_t>(rows_.size()); }

 private:
  std::int64_t frames_ = 0;
  FrontendTotals frontend_;
  BackendTotals backend_;
  std::vector<FrameRecord> rows_;
  int decode_stage_, frontend_stage_, backend_stage_;
};

}  // namespace voca::pipeline
