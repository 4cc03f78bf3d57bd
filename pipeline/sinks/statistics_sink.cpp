#include "pipeline/sinks/statistics_sink.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace voca::pipeline {

void DistanceHistogram::record(double px) {
  const double bin = std::floor(std::max(px, 0.0) / kBinPx);
  const int index = std::isfinite(bin) && bin < kBins ? static_cast<int>(bin) : kBins;
  ++bins_[static_cast<std::size_t>(index)];
  ++count_;
}

double DistanceHistogram::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<std::int64_t>(std::llround(std::clamp(q, 0.0, 1.0) * static_cast<double>(count_ - 1)));
  std::int64_t seen = 0;
  for (int b = 0; b <= kBins; ++b) {
    seen += bins_[static_cast<std::size_t>(b)];
    if (seen > rank) return b < kBins ? (b + 0.5) * kBinPx : std::numeric_limits<double>::infinity();
  }
  return std::numeric_limits<double>::infinity();
}

std::string DistanceHistogram::formatQuantile(double q) const {
  const double value = quantile(q);
  return std::isinf(value) ? fmt::format("> {:g}", kRangePx) : fmt::format("{:.3f}", value);
}

StatisticsSink::StatisticsSink(std::size_t row_capacity, int decode_stage, int frontend_stage, int backend_stage)
    : decode_stage_(decode_stage), frontend_stage_(frontend_stage), backend_stage_(backend_stage) {
  rows_.reserve(row_capacity);
}

namespace {

float serviceMs(const FrameSlot& slot, int stage) {
  if (stage < 0) return 0.f;
  return static_cast<float>(slot.timing[static_cast<std::size_t>(stage)].serviceMs());
}

float cpuMs(const FrameSlot& slot, int stage) {
  return stage < 0
             ? 0.f
             : static_cast<float>(static_cast<double>(slot.timing[static_cast<std::size_t>(stage)].cpu_ns) * 1e-6);
}

}  // namespace

void StatisticsSink::consume(const FrameSlot& slot) {
  const FrontendStats& s = slot.frontend_stats;
  FrontendTotals& f = frontend_;
  if (frames_ == 0) f.min_left = f.max_left = s.num_left;
  f.min_left = std::min(f.min_left, s.num_left);
  f.max_left = std::max(f.max_left, s.num_left);
  f.left_points += s.num_left;
  f.right_points += s.num_right;
  for (const TemporalStats& t : s.temporal) {
    f.previous += t.previous;
    f.kept += t.kept;
    f.rescued += t.rescued;
    f.consensus += t.consensus_rejections;
    f.tracked_plain += t.tracked_plain;
    f.tracked_prior += t.tracked_prior;
    f.with_vector += t.with_vector;
    f.distrusted += t.distrusted;
    f.prior_confirmed += t.prior_confirmed;
    f.flow_retried += t.flow_retried;
    f.flow_searched += t.flow_searched;
  }
  f.detected += s.detected;
  f.detected_right_only += s.detected_right_only;
  f.thinned += s.thinned;
  f.stereo_matched += s.stereo_matched;
  f.stereo_rematched += s.stereo_rematched;
  f.epipolar += s.epipolar_rejected;
  f.bridged_frames += (s.bridged[0] || s.bridged[1]) ? 1 : 0;
  for (const float d : s.guess_dist_plain_px) f.guess_plain.record(d);
  for (const float d : s.guess_dist_prior_px) f.guess_prior.record(d);

  const bool estimated = backend_stage_ >= 0;
  if (estimated) {
    backend_.keyframes += slot.pose.keyframe ? 1 : 0;
    backend_.resets += slot.pose.state == TrackingState::kReset ? 1 : 0;
    backend_.lost += slot.pose.state == TrackingState::kLost ? 1 : 0;
  }
  ++frames_;
  if (rows_.size() == rows_.capacity()) return;
  FrameRecord& r = rows_.emplace_back();
  r.frame_index = slot.frame.frame_index;
  r.t_ns = slot.frame.t_ns;
  r.missing_before = slot.frame.frames_missing_before;
  r.picture_type = pictureTypeName(slot.frame.motion[0].pictureType())[0];
  r.bridged = s.bridged[0] || s.bridged[1];
  r.left = s.num_left;
  r.right = s.num_right;
  r.kept = s.temporal[0].kept;
  r.lost = s.temporal[0].lost;
  r.rescued = s.temporal[0].rescued;
  r.consensus_rejections = s.temporal[0].consensus_rejections;
  r.detected = s.detected;
  if (estimated) {
    r.state = static_cast<std::uint8_t>(slot.pose.state);
    r.keyframe = slot.pose.keyframe;
    r.landmarks = slot.pose.num_landmarks;
    r.inliers = slot.pose.num_inliers;
  }
  r.decode_ms = serviceMs(slot, decode_stage_);
  r.frontend_ms = serviceMs(slot, frontend_stage_);
  r.backend_ms = serviceMs(slot, backend_stage_);
  r.frontend_cpu_ms = cpuMs(slot, frontend_stage_);
  r.backend_cpu_ms = cpuMs(slot, backend_stage_);
}

}  // namespace voca::pipeline
