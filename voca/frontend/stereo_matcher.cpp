#include "voca/frontend/stereo_matcher.h"

#include <algorithm>
#include <cmath>

#include "voca/geometry/so3.h"

namespace voca {

namespace {

// The centre of the detection mask (image_safe_radius_px): every camera model starts fx fy cx cy.
Eigen::Vector2f principalPoint(const CameraCalibration& camera) {
  const std::vector<double> intrinsics = camera.camera.params();
  return {static_cast<float>(intrinsics[2]), static_cast<float>(intrinsics[3])};
}

}  // namespace

StereoMatcher::StereoMatcher(const FrontendConfig& config, const StereoRig& rig, const RoundTripTracker& klt,
                             int max_points, int max_width, int max_height)
    : config_(config),
      klt_(klt),
      num_levels_(config.pyramid_levels + 1),
      round_trip2_(static_cast<float>(config.stereoRoundTripDist2())),
      max_points_(max_points),
      average_depth_m_(config.matching_default_depth_m) {
  for (std::size_t c = 0; c < 2; ++c) cameras_[c] = rig.cameras[c].camera;
  const SE3d T_cam0_cam1 = rig.T_cam0_cam1();
  T_cam1_cam0_ = T_cam0_cam1.inverse();
  // f0 ~ R f1 + t up to depth; f0 . (t x R f1) = 0. t normalised so the threshold is scale-free.
  const Eigen::Vector3d t = T_cam0_cam1.translation();
  essential_ = SO3d::hat(t.norm() > 0.0 ? Eigen::Vector3d(t.normalized()) : t) * T_cam0_cam1.rotationMatrix();

  left_detector_params_.grid_size_px = config_.grid_size_px;
  left_detector_params_.max_threshold = config_.detection_max_threshold;
  left_detector_params_.min_threshold = config_.detection_min_threshold;
  left_detector_params_.border_px = config_.detection_border_px;
  left_detector_params_.safe_radius_px = static_cast<float>(config_.image_safe_radius_px);
  left_detector_params_.safe_center = principalPoint(rig.cameras[0]);
  right_detector_params_ = left_detector_params_;
  right_detector_params_.safe_center = principalPoint(rig.cameras[1]);
  detector_ = GridDetector(max_width, max_height, config_.grid_size_px);
  new_points_.reserve(static_cast<std::size_t>(max_points_));
  if (config_.stereo_rematch) {
    for (auto* v : {&rematch_ids_, &merged_ids_}) v->reserve(static_cast<std::size_t>(max_points_));
    for (auto* v : {&rematch_points_, &merged_points_}) v->reserve(static_cast<std::size_t>(max_points_));
    for (auto* v : {&rematch_slots_, &merged_slots_}) v->reserve(static_cast<std::size_t>(max_points_));
  }
  if (config_.detection_nonoverlap) computeRightOverlap(rig);
}

void StereoMatcher::computeRightOverlap(const StereoRig& rig) {
  const int g = config_.grid_size_px;
  const int width = rig.cameras[1].width, height = rig.cameras[1].height;
  const int cells_x = (width + g - 1) / g, cells_y = (height + g - 1) / g;
  right_overlap_.assign(static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y), 0);
  // A cell overlaps when any of a 5x5 lattice of its pixels, put at the matching depth, projects
  // into the left image (inside the detection border, where the left camera would find corners).
  const double depth = config_.matching_default_depth_m;
  const double border = config_.detection_border_px;
  const SE3d T_cam0_cam1 = T_cam1_cam0_.inverse();
  for (int cy = 0; cy < cells_y; ++cy) {
    for (int cx = 0; cx < cells_x; ++cx) {
      bool seen = false;
      for (int j = 0; j < 5 && !seen; ++j) {
        for (int i = 0; i < 5 && !seen; ++i) {
          const double u = std::min(cx * g + (i + 0.5) * g / 5.0, width - 1.0);
          const double v = std::min(cy * g + (j + 0.5) * g / 5.0, height - 1.0);
          Eigen::Vector3d bearing;
          Eigen::Vector2d uv;
          if (!cameras_[1].unproject(Eigen::Vector2d(u, v), bearing)) continue;
          if (!cameras_[0].project(T_cam0_cam1 * (bearing * depth), uv)) continue;
          seen = uv.x() >= border && uv.y() >= border && uv.x() < rig.cameras[0].width - border &&
                 uv.y() < rig.cameras[0].height - border;
        }
      }
      right_overlap_[static_cast<std::size_t>(cy * cells_x + cx)] = seen ? 1 : 0;
    }
  }
}

Eigen::Vector2f StereoMatcher::stereoGuess(const Eigen::Vector2f& p) const {
  const double depth =
      config_.matching_guess == StereoGuess::kAverageDepth ? average_depth_m_ : config_.matching_default_depth_m;
  Eigen::Vector3d bearing;
  Eigen::Vector2d uv;
  if (cameras_[0].unproject(p.cast<double>(), bearing) && cameras_[1].project(T_cam1_cam0_ * (bearing * depth), uv)) {
    return uv.cast<float>();
  }
  return p;
}

void StereoMatcher::detectAndMatch(GrayView left_image, CameraTracks& left, CameraTracks& right,
                                   std::uint64_t& next_track_id, FrontendStats& stats) {
  new_points_.clear();
  const int room = max_points_ - static_cast<int>(left.points.size());
  if (room <= 0) return;
  stats.detected = detector_.detect(left_image, left.points, left_detector_params_, room, new_points_);
  const int right_room = max_points_ - static_cast<int>(right.points.size());
  for (const Eigen::Vector2f& p : new_points_) {
    const std::uint64_t id = next_track_id++;
    const int left_slot = left.addDetected(id, p, klt_.pattern());
    if (stats.stereo_matched >= right_room) continue;
    const Eigen::Vector2f guess = stereoGuess(p);
    Eigen::Vector2f matched;
    const int right_slot = right.free_slots.acquire();
    if (klt_.track(left.templates.built(left_slot), left.cur(), right.cur(), p, guess - p, num_levels_, round_trip2_,
                   right.templates, right_slot, matched)) {
      right.append(id, matched, right_slot);
      ++stats.stereo_matched;
    } else {
      right.free_slots.release(right_slot);
    }
  }
}

void StereoMatcher::rematch(CameraTracks& left, CameraTracks& right, FrontendStats& stats) {
  rematch_ids_.clear();
  rematch_points_.clear();
  rematch_slots_.clear();
  int room = max_points_ - static_cast<int>(right.points.size());
  // Both id lists ascend: one pass finds the left tracks without a right view.
  std::size_t r = 0;
  for (std::size_t l = 0; l < left.ids.size() && room > 0; ++l) {
    const std::uint64_t id = left.ids[l];
    while (r < right.ids.size() && right.ids[r] < id) ++r;
    if (r < right.ids.size() && right.ids[r] == id) continue;
    const Eigen::Vector2f& p = left.points[l];
    const Eigen::Vector2f guess = stereoGuess(p);
    Eigen::Vector2f matched;
    const int right_slot = right.free_slots.acquire();
    // The left slot holds the point's templates in the current image (its backward track built them).
    if (klt_.track(left.templates.ensureBuilt(left.slots[l], left.cur(), p, num_levels_, klt_.pattern()), left.cur(),
                   right.cur(), p, guess - p, num_levels_, round_trip2_, right.templates, right_slot, matched)) {
      rematch_ids_.push_back(id);
      rematch_points_.push_back(matched);
      rematch_slots_.push_back(right_slot);
      --room;
    } else {
      right.free_slots.release(right_slot);
    }
  }
  stats.stereo_rematched = static_cast<int>(rematch_ids_.size());
  if (rematch_ids_.empty()) return;
  merged_ids_.clear();
  merged_points_.clear();
  merged_slots_.clear();
  std::size_t a = 0, b = 0;
  while (a < right.ids.size() || b < rematch_ids_.size()) {
    const bool take_right = b == rematch_ids_.size() || (a < right.ids.size() && right.ids[a] < rematch_ids_[b]);
    if (take_right) {
      merged_ids_.push_back(right.ids[a]);
      merged_points_.push_back(right.points[a]);
      merged_slots_.push_back(right.slots[a]);
      ++a;
    } else {
      merged_ids_.push_back(rematch_ids_[b]);
      merged_points_.push_back(rematch_points_[b]);
      merged_slots_.push_back(rematch_slots_[b]);
      ++b;
    }
  }
  // Swapping keeps both sets of buffers at their reserved capacity: nothing is allocated.
  right.ids.swap(merged_ids_);
  right.points.swap(merged_points_);
  right.slots.swap(merged_slots_);
}

void StereoMatcher::detectRightOnly(GrayView right_image, CameraTracks& right, std::uint64_t& next_track_id,
                                    FrontendStats& stats) {
  new_points_.clear();
  const int room = max_points_ - static_cast<int>(right.points.size());
  if (room <= 0) return;
  stats.detected_right_only =
      detector_.detect(right_image, right.points, right_detector_params_, room, new_points_, right_overlap_);
  // Ids are issued in increasing order, so the right list stays sorted for filterEpipolar's merge.
  for (const Eigen::Vector2f& p : new_points_) {
    right.addDetected(next_track_id++, p, klt_.pattern());
  }
}

void StereoMatcher::filterEpipolar(const CameraTracks& left, CameraTracks& right, FrontendStats& stats) {
  // Both id lists are ascending (ids are issued in increasing order and removals keep the order),
  // so one merge pass pairs them.
  std::size_t l = 0;
  const float threshold = static_cast<float>(config_.epipolar_error);
  right.retain([&](std::size_t r, std::size_t) {
    const std::uint64_t id = right.ids[r];
    while (l < left.ids.size() && left.ids[l] < id) ++l;
    if (l == left.ids.size() || left.ids[l] != id) return true;  // a right-only track
    Eigen::Vector3d f0, f1;
    const bool ok0 = cameras_[0].unproject(left.points[l].cast<double>(), f0);
    const bool ok1 = cameras_[1].unproject(right.points[r].cast<double>(), f1);
    const bool keep = ok0 && ok1 && std::abs(f0.dot(essential_ * f1)) <= threshold;
    if (!keep) ++stats.epipolar_rejected;
    return keep;
  });
}

}  // namespace voca
