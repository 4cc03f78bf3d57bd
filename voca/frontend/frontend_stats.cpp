#include "voca/frontend/frontend_stats.h"

namespace voca {

TemporalStats& TemporalStats::operator+=(const TemporalStats& other) {
  previous += other.previous;
  with_vector += other.with_vector;
  tracked_plain += other.tracked_plain;
  tracked_prior += other.tracked_prior;
  kept += other.kept;
  lost += other.lost;
  rescued += other.rescued;
  flow_retried += other.flow_retried;
  flow_searched += other.flow_searched;
  consensus_rejections += other.consensus_rejections;
  distrusted += other.distrusted;
  prior_confirmed += other.prior_confirmed;
  return *this;
}

void FrontendStats::reserve(std::size_t max_points) {
  guess_dist_plain_px.reserve(2 * max_points);
  guess_dist_prior_px.reserve(2 * max_points);
}

void FrontendStats::clear() {
  temporal = {};
  bridged = {false, false};
  detected = detected_right_only = stereo_matched = stereo_rematched = epipolar_rejected = thinned = num_left =
      num_right = 0;
  guess_dist_plain_px.clear();
  guess_dist_prior_px.clear();
  time_ms = 0.0;
}

}  // namespace voca
