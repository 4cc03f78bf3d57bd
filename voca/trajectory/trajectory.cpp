#include "voca/trajectory/trajectory.h"

#include <algorithm>
#include <cstdint>
#include <iterator>

namespace voca {

Trajectory changeBodyFrame(const Trajectory& trajectory, const SE3d& T_body_new) {
  Trajectory out;
  out.has_timestamps = trajectory.has_timestamps;
  out.poses.reserve(trajectory.poses.size());
  for (const TimedPose& pose : trajectory.poses) out.poses.push_back({pose.t_ns, pose.T_world_body * T_body_new});
  return out;
}

std::optional<SE3d> interpolatePose(const Trajectory& trajectory, int64_t t_ns) {
  const std::vector<TimedPose>& poses = trajectory.poses;
  if (poses.empty() || t_ns < poses.front().t_ns || t_ns > poses.back().t_ns) return std::nullopt;
  const auto after = std::upper_bound(poses.begin(), poses.end(), t_ns,
                                      [](int64_t t, const TimedPose& pose) { return t < pose.t_ns; });
  const TimedPose& p0 = *std::prev(after);
  if (p0.t_ns == t_ns || after == poses.end()) return p0.T_world_body;
  const TimedPose& p1 = *after;
  // p0.t_ns <= t_ns < p1.t_ns: the differences are in [0, 2^64), exact in unsigned arithmetic even
  // where the signed subtraction would overflow.
  const auto since = [](int64_t later, int64_t earlier) {
    return static_cast<double>(static_cast<uint64_t>(later) - static_cast<uint64_t>(earlier));
  };
  const double alpha = since(t_ns, p0.t_ns) / since(p1.t_ns, p0.t_ns);
  const Eigen::Vector3d t = (1.0 - alpha) * p0.T_world_body.translation() + alpha * p1.T_world_body.translation();
  const Eigen::Quaterniond q = p0.T_world_body.unitQuaternion().slerp(alpha, p1.T_world_body.unitQuaternion());
  return SE3d(q, t);
}

}  // namespace voca
