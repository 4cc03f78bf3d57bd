#include "voca/eval/metrics.h"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca {

std::string_view alignModeName(AlignMode mode) {
  switch (mode) {
    case AlignMode::kNone:
      return "none";
    case AlignMode::kSe3:
      return "se3";
    case AlignMode::kSim3:
      return "sim3";
  }
  return "unknown";
}

std::string_view deltaUnitName(DeltaUnit unit) { return unit == DeltaUnit::kFrames ? "frames" : "m"; }

Alignment umeyamaAlignment(std::span<const Eigen::Vector3d> p_est, std::span<const Eigen::Vector3d> p_gt,
                           bool with_scale) {
  if (p_est.size() != p_gt.size()) {
    throw InputError(fmt::format("alignment needs corresponding points, got {} and {}", p_est.size(), p_gt.size()));
  }
  if (p_est.size() < 3) {
    throw InputError(fmt::format("alignment needs at least 3 associated poses, got {}", p_est.size()));
  }
  const double n = static_cast<double>(p_est.size());
  Eigen::Vector3d mean_est = Eigen::Vector3d::Zero(), mean_gt = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p_est.size(); ++i) {
    mean_est += p_est[i];
    mean_gt += p_gt[i];
  }
  mean_est /= n;
  mean_gt /= n;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double variance_est = 0.0;
  for (std::size_t i = 0; i < p_est.size(); ++i) {
    const Eigen::Vector3d d_est = p_est[i] - mean_est;
    covariance += (p_gt[i] - mean_gt) * d_est.transpose();
    variance_est += d_est.squaredNorm();
  }
  covariance /= n;
  variance_est /= n;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s = Eigen::Vector3d::Ones();
  // A reflection would fit better for degenerate or mirrored data; Umeyama's S keeps a rotation.
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s.z() = -1.0;
  const Eigen::Matrix3d rotation = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();

  Alignment alignment;
  if (with_scale) {
    if (!(variance_est > 0.0)) throw InputError("scale alignment needs an estimate that moves");
    alignment.scale = svd.singularValues().dot(s) / variance_est;
  }
  alignment.T_gt_est = SE3d(SO3d(rotation), mean_gt - alignment.scale * (rotation * mean_est));
  return alignment;
}

ErrorStats errorStatistics(std::span<const double> errors) {
  ErrorStats stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  const double n = static_cast<double>(errors.size());
  double sum = 0.0;
  for (const double e : errors) {
    sum += e;
    stats.sse += e * e;
  }
  stats.mean = sum / n;
  stats.rmse = std::sqrt(stats.sse / n);
  double squared_deviation = 0.0;
  for (const double e : errors) squared_deviation += (e - stats.mean) * (e - stats.mean);
  stats.std = std::sqrt(squared_deviation / n);
  std::vector<double> sorted(errors.begin(), errors.end());
  std::sort(sorted.begin(), sorted.end());
  stats.min = sorted.front();
  stats.max = sorted.back();
  stats.median = quantileInPlace(sorted, 0.5);
  return stats;
}

AteResult absoluteTrajectoryError(std::span<const Eigen::Vector3d> p_world_est,
                                  std::span<const Eigen::Vector3d> p_world_gt, AlignMode align) {
  if (p_world_est.size() != p_world_gt.size() || p_world_est.empty()) {
    throw InputError(fmt::format("ATE needs associated poses, got {} estimated and {} ground-truth", p_world_est.size(),
                                 p_world_gt.size()));
  }
  AteResult result;
  result.align = align;
  if (align != AlignMode::kNone) {
    result.alignment = umeyamaAlignment(p_world_est, p_world_gt, align == AlignMode::kSim3);
  }
  result.errors.reserve(p_world_est.size());
  for (std::size_t i = 0; i < p_world_est.size(); ++i) {
    result.errors.push_back((result.alignment.apply(p_world_est[i]) - p_world_gt[i]).norm());
  }
  result.stats = errorStatistics(result.errors);
  return result;
}

AteResult absoluteTrajectoryError(std::span<const SE3d> T_world_est, std::span<const SE3d> T_world_gt,
                                  AlignMode align) {
  std::vector<Eigen::Vector3d> p_est, p_gt;
  for (const SE3d& T : T_world_est) p_est.push_back(T.translation());
  for (const SE3d& T : T_world_gt) p_gt.push_back(T.translation());
  return absoluteTrajectoryError(p_est, p_gt, align);
}

std::vector<std::pair<std::size_t, std::size_t>> relativePosePairs(std::span<const Eigen::Vector3d> p_world_body,
                                                                   double delta, DeltaUnit unit) {
  std::vector<std::size_t> ids;
  if (unit == DeltaUnit::kFrames) {
    if (!(delta >= 1.0) || delta != std::floor(delta)) {
      throw InputError(fmt::format("a delta in frames must be a whole number >= 1, got {}", delta));
    }
    const std::size_t step = static_cast<std::size_t>(delta);
    for (std::size_t i = 0; i < p_world_body.size(); i += step) ids.push_back(i);
  } else {
    if (!(delta > 0.0)) throw InputError(fmt::format("a delta in metres must be > 0, got {}", delta));
    // evo's filter_pairs_by_path: the path restarts at each selected pose; the first pose is not
    // selected itself, only the first one a full delta away from it.
    double path_m = 0.0;
    for (std::size_t i = 1; i < p_world_body.size(); ++i) {
      path_m += (p_world_body[i] - p_world_body[i - 1]).norm();
      if (path_m >= delta) {
        ids.push_back(i);
        path_m = 0.0;
      }
    }
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  return pairs;
}

namespace {

// Inverse of a rigid transform through the transposed rotation block (evo's se3_inverse).
Eigen::Matrix4d rigidInverse(const Eigen::Matrix4d& T) {
  Eigen::Matrix4d inverse = Eigen::Matrix4d::Identity();
  inverse.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>().transpose();
  inverse.topRightCorner<3, 1>() = -(inverse.topLeftCorner<3, 3>() * T.topRightCorner<3, 1>());
  return inverse;
}

}  // namespace

RteResult relativeTrajectoryError(std::span<const Eigen::Matrix4d> T_world_est,
                                  std::span<const Eigen::Matrix4d> T_world_gt, double delta, DeltaUnit unit) {
  if (T_world_est.size() != T_world_gt.size()) {
    throw InputError(fmt::format("RTE needs associated poses, got {} estimated and {} ground-truth", T_world_est.size(),
                                 T_world_gt.size()));
  }
  RteResult result;
  result.delta = delta;
  result.unit = unit;
  // evo forms the pairs on the estimate (this matters only for a delta in metres).
  std::vector<Eigen::Vector3d> p_est;
  p_est.reserve(T_world_est.size());
  for (const Eigen::Matrix4d& T : T_world_est) p_est.push_back(T.topRightCorner<3, 1>());
  result.pairs = relativePosePairs(p_est, delta, unit);
  result.errors.reserve(result.pairs.size());
  for (const auto& [i, j] : result.pairs) {
    const Eigen::Matrix4d T_gti_gtj = rigidInverse(T_world_gt[i]) * T_world_gt[j];
    const Eigen::Matrix4d T_esti_estj = rigidInverse(T_world_est[i]) * T_world_est[j];
    const Eigen::Matrix4d error = rigidInverse(T_gti_gtj) * T_esti_estj;
    result.errors.push_back(error.topRightCorner<3, 1>().norm());
  }
  result.stats = errorStatistics(result.errors);
  return result;
}

RteResult relativeTrajectoryError(std::span<const SE3d> T_world_est, std::span<const SE3d> T_world_gt, double delta,
                                  DeltaUnit unit) {
  std::vector<Eigen::Matrix4d> est, gt;
  for (const SE3d& T : T_world_est) est.push_back(T.matrix());
  for (const SE3d& T : T_world_gt) gt.push_back(T.matrix());
  return relativeTrajectoryError(std::span<const Eigen::Matrix4d>(est), std::span<const Eigen::Matrix4d>(gt), delta,
                                 unit);
}

}  // namespace voca
