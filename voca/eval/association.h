#pragma once
// Pairing estimated and ground-truth poses by timestamp (evo's nearest-time association) or index.

#include <cstddef>
#include <vector>

#include "voca/trajectory/trajectory.h"

namespace voca {

// Index pairs into an estimate and a ground truth, in the order evo produces them, with statistics.
struct PoseAssociation {
  std::vector<std::size_t> est_index;
  std::vector<std::size_t> gt_index;
  bool by_index = false;      // KITTI without timestamps: pose i with pose i
  double max_diff_s = 0.0;    // the tolerance used (0 for index pairing)
  double max_abs_dt_s = 0.0;  // largest |t_est - t_gt| among the pairs
  double mean_abs_dt_s = 0.0;
  std::size_t reused_poses = 0;  // poses of the longer trajectory paired more than once (evo allows it)

  std::size_t size() const { return est_index.size(); }
};

// Associates like evo's sync.associate_trajectories(ref, est, max_diff): each pose of the
// trajectory with fewer poses (the estimate on a tie) is paired with the nearest-in-time pose of
// the other (the earlier one on an exact tie) if |dt| <= max_diff_s; unmatched poses are dropped.
// When neither trajectory has timestamps (KITTI) the poses are paired by index, which needs equal
// counts, as in evo. Throws InputError when the two cannot be paired or no pair is found.
PoseAssociation associateTrajectories(const Trajectory& est, const Trajectory& gt, double max_diff_s = 0.01);

}  // namespace voca
