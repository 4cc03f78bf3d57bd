#pragma once
// Trajectory error metrics as the paper (and evo) define them: Umeyama alignment, ATE and RTE.

#include <cstddef>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "voca/geometry/se3.h"

namespace voca {

// A similarity transform p_gt = scale * (R p_est) + t, stored as T_gt_est = (R, t) and the scale.
struct Alignment {
  SE3d T_gt_est;
  double scale = 1.0;

  Eigen::Vector3d apply(const Eigen::Vector3d& p_est) const {
    return scale * (T_gt_est.so3() * p_est) + T_gt_est.translation();
  }
};

// How the estimate is aligned to the ground truth before ATE: not at all, rigidly (the paper:
// stereo has metric scale), or with scale (monocular).
enum class AlignMode { kNone, kSe3, kSim3 };
std::string_view alignModeName(AlignMode mode);

// Umeyama's closed-form least-squares alignment of corresponding points (gt ~ scale R est + t).
// Throws InputError for fewer than 3 points or mismatched sizes.
Alignment umeyamaAlignment(std::span<const Eigen::Vector3d> p_est, std::span<const Eigen::Vector3d> p_gt,
                           bool with_scale);

// Statistics of an error sequence, as evo reports them (std is the population deviation, the
// median of an even count is the mean of the middle two).
struct ErrorStats {
  double rmse = 0.0, mean = 0.0, median = 0.0, std = 0.0, min = 0.0, max = 0.0, sse = 0.0;
  std::size_t count = 0;
};
ErrorStats errorStatistics(std::span<const double> errors);

// ATE over associated pose sequences (same length, index i of one corresponds to index i of the other).
struct AteResult {
  ErrorStats stats;
  AlignMode align = AlignMode::kSe3;
  Alignment alignment;
  std::vector<double> errors;  // |t_gt_i - align(t_est_i)| per pose [m]
};
AteResult absoluteTrajectoryError(std::span<const SE3d> T_world_est, std::span<const SE3d> T_world_gt, AlignMode align);
// The same on positions alone (ATE ignores orientations).
AteResult absoluteTrajectoryError(std::span<const Eigen::Vector3d> p_world_est,
                                  std::span<const Eigen::Vector3d> p_world_gt, AlignMode align);

// The spacing of RTE pairs: a number of poses, or travelled path length in metres (evo's -u m).
enum class DeltaUnit { kFrames, kMeters };
std::string_view deltaUnitName(DeltaUnit unit);

// Consecutive index pairs as evo forms them. Frames: (0,d), (d,2d), ... Metres: the poses where
// the path travelled since the previous such pose first reaches delta, paired consecutively.
std::vector<std::pair<std::size_t, std::size_t>> relativePosePairs(std::span<const Eigen::Vector3d> p_world_body,
                                                                   double delta, DeltaUnit unit);

// RTE over associated pose sequences, without alignment: for each pair (i, j) formed on the
// estimate, the translation of (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), Q ground truth, P estimate.
struct RteResult {
  ErrorStats stats;
  double delta = 6.0;
  DeltaUnit unit = DeltaUnit::kFrames;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::vector<double> errors;  // [m]
};
RteResult relativeTrajectoryError(std::span<const SE3d> T_world_est, std::span<const SE3d> T_world_gt, double delta,
                                  DeltaUnit unit);
// The same on 4x4 matrices, inverted as rigid transforms ([R^T, -R^T t]) without re-orthonormalising
// them, as evo does: this reproduces evo on KITTI rows, whose rotations are rounded (Trajectory::raw_matrices).
RteResult relativeTrajectoryError(std::span<const Eigen::Matrix4d> T_world_est,
                                  std::span<const Eigen::Matrix4d> T_world_gt, double delta, DeltaUnit unit);

}  // namespace voca
