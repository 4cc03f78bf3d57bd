#pragma once
// What the frontend reports of each frame: counters per step, the guess distances of the paper's
// Fig. 5, and a trace per tracked point for overlays.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace voca {

// Temporal tracking of one camera in one frame.
struct TemporalStats {
  int previous = 0;       // points of the previous frame
  int with_vector = 0;    // of these, how many had a motion vector (possibly bridged)
  int tracked_plain = 0;  // successful tracks started from the previous position
  int tracked_prior = 0;  // successful tracks started from the MV prior
  int kept = 0;
  int lost = 0;
  int rescued = 0;       // kept from the prior after the plain track was tried and failed
  int flow_retried = 0;  // kept from the previous frame's image flow after every other guess failed
  // 1 when that retry started from the whole image's searched shift instead: no step had measured
  // the camera's flow yet (ImageShiftSearch).
  int flow_searched = 0;
  int consensus_rejections = 0;
  int distrusted = 0;       // vectors the codec-confidence checks rejected (counted in with_vector too)
  int prior_confirmed = 0;  // prior tracks not run: the vector landed near the plain track's result
  bool operator==(const TemporalStats&) const = default;
  // Adds every counter (the counts of two shares of one camera's points).
  TemporalStats& operator+=(const TemporalStats& other);
};

// What one call of KltFrontend::track did.
struct FrontendStats {
  std::int64_t frame_index = 0;
  std::array<TemporalStats, 2> temporal{};
  std::array<bool, 2> bridged{false, false};  // the camera's prior came from an earlier P-frame
  int detected = 0;                           // new left points
  int detected_right_only = 0;                // new right points where the left camera does not see
  int stereo_matched = 0;                     // of the new points, found in the right image
  int stereo_rematched = 0;                   // left tracks without a right view found there again (stereo_rematch)
  int epipolar_rejected = 0;                  // right observations dropped by the epipolar check
  int thinned = 0;                            // left tracks dropped next to an older one (thin_when_full_px)
  int num_left = 0, num_right = 0;            // observations output
  // For every kept temporal track that had a motion vector, the distance from each initial guess
  // (previous position: plain; previous position + vector: prior) to the converged position, in
  // pixels, both cameras (the paper's Fig. 5). Paired by index.
  std::vector<float> guess_dist_plain_px, guess_dist_prior_px;
  double time_ms = 0.0;

  void reserve(std::size_t max_points);
  void clear();
};

// Per-point record of the last temporal step, for overlays (the paper's Fig. 1).
struct PointTrace {
  std::uint64_t track_id = 0;
  Eigen::Vector2f previous_px = Eigen::Vector2f::Zero();
  Eigen::Vector2f prior_px = Eigen::Vector2f::Zero();  // previous + motion vector, when has_prior
  Eigen::Vector2f tracked_px = Eigen::Vector2f::Zero();
  bool has_prior = false;
  bool kept = false;
};

}  // namespace voca
