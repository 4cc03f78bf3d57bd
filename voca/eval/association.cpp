#include "voca/eval/association.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "voca/core/error.h"

namespace voca {

namespace {

// Index of the pose nearest to t_ns in poses sorted by time (repeats allowed); the earlier one when two are equally
// near (numpy's argmin returns the first minimum).
std::size_t nearestIndex(const std::vector<TimedPose>& poses, int64_t t_ns) {
  const auto it =
      std::lower_bound(poses.begin(), poses.end(), t_ns, [](const TimedPose& p, int64_t t) { return p.t_ns < t; });
  if (it == poses.begin()) return 0;
  if (it == poses.end()) return poses.size() - 1;
  const std::size_t after = static_cast<std::size_t>(it - poses.begin());
  const int64_t d_before = t_ns - poses[after - 1].t_ns;
  const int64_t d_after = poses[after].t_ns - t_ns;
  std::size_t nearest = d_before <= d_after ? after - 1 : after;
  // Repeated timestamps: the first of them, again like argmin.
  while (nearest > 0 && poses[nearest - 1].t_ns == poses[nearest].t_ns) --nearest;
  return nearest;
}

}  // namespace

PoseAssociation associateTrajectories(const Trajectory& est, const Trajectory& gt, double max_diff_s) {
  PoseAssociation result;
  if (est.poses.empty() || gt.poses.empty()) throw InputError("cannot associate an empty trajectory");

  if (!est.has_timestamps || !gt.has_timestamps) {
    if (est.has_timestamps != gt.has_timestamps) {
      throw InputError(fmt::format(
          "the {} has no timestamps (KITTI poses without a times file) but the {} does: give the KITTI file its "
          "times.txt so the poses can be associated by time",
          est.has_timestamps ? "ground truth" : "estimate", est.has_timestamps ? "estimate" : "ground truth"));
    }
    if (est.poses.size() != gt.poses.size()) {
      throw InputError(fmt::format(
          "KITTI poses without timestamps are paired by index, but the estimate has {} poses and the ground truth "
          "{}: give both their times files",
          est.poses.size(), gt.poses.size()));
    }
    result.by_index = true;
    for (std::size_t i = 0; i < est.poses.size(); ++i) {
      result.est_index.push_back(i);
      result.gt_index.push_back(i);
    }
    return result;
  }

  if (!(max_diff_s >= 0.0)) throw InputError(fmt::format("max time difference must be >= 0 s, got {}", max_diff_s));
  result.max_diff_s = max_diff_s;
  // evo calls associate_trajectories(ref, est): the estimate is "second" and counts as the
  // shorter one unless it has strictly more poses.
  const bool est_longer = est.poses.size() > gt.poses.size();
  const std::vector<TimedPose>& shorter = est_longer ? gt.poses : est.poses;
  const std::vector<TimedPose>& longer = est_longer ? est.poses : gt.poses;
  std::vector<int> uses(longer.size(), 0);
  double sum_abs_dt = 0.0;
  for (std::size_t i = 0; i < shorter.size(); ++i) {
    const std::size_t j = nearestIndex(longer, shorter[i].t_ns);
    // Compared in seconds, as evo does, so a boundary case rounds the same way.
    const double abs_dt_s = std::abs(static_cast<double>(longer[j].t_ns - shorter[i].t_ns)) * 1e-9;
    if (abs_dt_s > max_diff_s) continue;
    result.est_index.push_back(est_longer ? j : i);
    result.gt_index.push_back(est_longer ? i : j);
    if (uses[j]++ == 1) ++result.reused_poses;
    result.max_abs_dt_s = std::max(result.max_abs_dt_s, abs_dt_s);
    sum_abs_dt += abs_dt_s;
  }
  if (result.est_index.empty()) {
    throw InputError(fmt::format(
        "no timestamps of the estimate ({} poses, {:.3f}..{:.3f} s) are within {} s of the ground truth's ({} poses, "
        "{:.3f}..{:.3f} s)",
        est.poses.size(), est.poses.front().t_ns * 1e-9, est.poses.back().t_ns * 1e-9, max_diff_s, gt.poses.size(),
        gt.poses.front().t_ns * 1e-9, gt.poses.back().t_ns * 1e-9));
  }
  result.mean_abs_dt_s = sum_abs_dt / static_cast<double>(result.est_index.size());
  return result;
}

}  // namespace voca
