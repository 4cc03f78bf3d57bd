#include "voca/backend/estimator.h"

#include <fmt/core.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>

#include "voca/core/error.h"

namespace voca {

namespace {

// A landmark whose outlier observations leave fewer than this many is dropped as a whole
// (Basalt's filterOutliers(threshold, 4)): with so few views the remaining ones are suspect too.
constexpr int kFilterMinObservations = 4;
// Relative cost decrease below which LM stops.
constexpr double kConvergedRelativeDecrease = 1e-6;
// Regularisation of blocks that are inverted without damping (marginalisation); far below any
// real information (a 1 px error at 1 m gives about 1e5 on the pose diagonal).
constexpr double kTinyRegularization = 1e-9;

Eigen::Matrix<double, 6, 1> poseDelta(const SE3d& T, const SE3d& T_lin) {
  Eigen::Matrix<double, 6, 1> d;
  d.head<3>() = T.translation() - T_lin.translation();
  d.tail<3>() = (T.so3() * T_lin.so3().inverse()).log();
  return d;
}

void applyPoseIncrement(SE3d& T, const Eigen::Matrix<double, 6, 1>& xi) {
  T.translation() += xi.head<3>();
  T.so3() = SO3d::exp(xi.tail<3>()) * T.so3();
}

}  // namespace

std::string_view trackingStateName(TrackingState state) {
  switch (state) {
    case TrackingState::kTracking:
      return "tracking";
    case TrackingState::kReset:
      return "reset";
    case TrackingState::kLost:
      return "lost";
  }
  return "?";
}

std::string_view failureReasonName(FailureReason reason) {
  switch (reason) {
    case FailureReason::kNone:
      return "none";
    case FailureReason::kTooFewInliers:
      return "too few inliers";
    case FailureReason::kExplodingCost:
      return "exploding cost";
    case FailureReason::kImpossibleMotion:
      return "impossible motion";
    case FailureReason::kTooFewStereoPoints:
      return "too few stereo points";
  }
  return "?";
}

VoEstimator::VoEstimator(const BackendConfig& config, const StereoRig& rig)
    : config_(config), id_to_landmark_(config.max_landmarks) {
  validateBackendConfig(config_, "backend");
  if (rig.cameras.size() < 2) throw InputError("backend: the calibration needs two cameras (stereo)");
  for (int c = 0; c < 2; ++c) cameras_[static_cast<std::size_t>(c)] = rig.cameras[static_cast<std::size_t>(c)].camera;
  T_body_cam0_ = rig.cameras[0].T_body_cam;
  T_cam0_cam_[0] = SE3d();
  T_cam0_cam_[1] = rig.T_cam0_cam1();
  for (std::size_t c = 0; c < 2; ++c) cam0_cam_[c].set(T_cam0_cam_[c]);
  huber_px_ = config_.obs_huber_thresh_px;
  inv_var_ = 1.0 / (config_.obs_std_dev_px * config_.obs_std_dev_px);

  const auto n = static_cast<std::size_t>(config_.max_landmarks);
  landmarks_.resize(n);
  lin_.resize(n);
  free_landmarks_.reserve(n);
  alive_.reserve(n);
  scratch_landmarks_.reserve(n);
  scratch_ids_.reserve(static_cast<std::size_t>(config_.max_observations_per_camera));
  for (Frame& f : frames_) {
    for (auto& o : f.obs) o.reserve(static_cast<std::size_t>(config_.max_observations_per_camera));
  }
  reset();
}

void VoEstimator::reset() {
  for (Frame& f : frames_) {
    f.active = f.keyframe = f.in_prior = false;
    for (auto& o : f.obs) o.clear();
  }
  free_landmarks_.clear();
  alive_.clear();
  for (int i = config_.max_landmarks - 1; i >= 0; --i) {
    landmarks_[static_cast<std::size_t>(i)].alive = false;
    free_landmarks_.push_back(i);
  }
  id_to_landmark_.clear();
  num_landmarks_ = 0;
  prior_H_.setZero();
  prior_g_.setZero();
  prior_c_ = 0.0;
  initialized_ = false;
  pending_reset_ = false;
  last_good_T_w_c_ = T_body_cam0_;  // the body starts at the world origin
  previous_T_w_c_ = last_good_T_w_c_;
  velocity_ = SE3d();
  frames_since_kf_ = 0;
}

int VoEstimator::numKeyframes() const {
  int n = 0;
  for (const Frame& f : frames_) n += f.active && f.keyframe;
  return n;
}

int VoEstimator::numObs(const Landmark& lm) const { return std::popcount(lm.mask); }

bool VoEstimator::residual(const Landmark& lm, int frame, int cam, Eigen::Vector2d& r,
                           ReprojectionJacobians* jac) const {
  Eigen::Vector2d uv;
  const auto c = static_cast<std::size_t>(cam);
  if (!reprojectLandmark(cameras_[c], frames_[static_cast<std::size_t>(lm.host)].T_w_c,
                         frames_[static_cast<std::size_t>(frame)].T_w_c, T_cam0_cam_[c], lm.s, lm.rho, uv, jac)) {
    return false;
  }
  r = uv - lm.px[static_cast<std::size_t>(frame)][c];
  return r.allFinite();
}

VoEstimator::FramePoses VoEstimator::framePoses() const {
  FramePoses poses;
  for (std::size_t f = 0; f < poses.size(); ++f) poses[f].set(frames_[f].T_w_c);
  return poses;
}

bool VoEstimator::residual(const FramePoses& poses, const Landmark& lm, int frame, int cam, Eigen::Vector2d& r,
                           ReprojectionJacobians* jac) const {
  Eigen::Vector2d uv;
  const auto c = static_cast<std::size_t>(cam);
  if (!reprojectLandmark(cameras_[c], poses[static_cast<std::size_t>(lm.host)], poses[static_cast<std::size_t>(frame)],
                         cam0_cam_[c], lm.s, lm.rho, uv, jac)) {
    return false;
  }
  r = uv - lm.px[static_cast<std::size_t>(frame)][c];
  return r.allFinite();
}

// ---- frames and observations ------------------------------------------------------------------

int VoEstimator::allocateFrame(const TrackedStereoFrame& frame, const SE3d& T_w_c) {
  int slot = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    if (!frames_[static_cast<std::size_t>(i)].active) {
      slot = i;
      break;
    }
  }
  // The window never holds more than max_keyframes + 1 <= kMaxWindowFrames frames.
  if (slot < 0) throw std::logic_error("VoEstimator: window overflow");
  Frame& f = frames_[static_cast<std::size_t>(slot)];
  f.active = true;
  f.keyframe = false;
  f.in_prior = false;
  f.t_ns = frame.t_ns;
  f.frame_index = frame.frame_index;
  f.sequence = sequence_++;
  f.T_w_c = T_w_c;
  const std::size_t capacity = static_cast<std::size_t>(config_.max_observations_per_camera);
  for (std::size_t c = 0; c < 2; ++c) {
    auto& list = f.obs[c];
    list.clear();
    for (const KeypointObservation& o : frame.observations[c]) {
      if (list.size() >= capacity) break;
      if (!o.px.allFinite()) continue;
      list.push_back({o.track_id, o.px.cast<double>()});
    }
    std::sort(list.begin(), list.end(), [](const Observation& a, const Observation& b) { return a.id < b.id; });
    list.erase(
        std::unique(list.begin(), list.end(), [](const Observation& a, const Observation& b) { return a.id == b.id; }),
        list.end());
  }
  return slot;
}

void VoEstimator::attachObservations(int frame) {
  Frame& f = frames_[static_cast<std::size_t>(frame)];
  for (int c = 0; c < 2; ++c) {
    for (const Observation& o : f.obs[static_cast<std::size_t>(c)]) {
      const int index = id_to_landmark_.find(o.id);
      if (index < 0) continue;
      Landmark& lm = landmarks_[static_cast<std::size_t>(index)];
      lm.mask |= 1u << maskBit(frame, c);
      lm.px[static_cast<std::size_t>(frame)][static_cast<std::size_t>(c)] = o.px;
    }
  }
}

void VoEstimator::removeLandmark(int index) {
  Landmark& lm = landmarks_[static_cast<std::size_t>(index)];
  if (!lm.alive) return;
  id_to_landmark_.erase(lm.id);
  lm.alive = false;
  lm.mask = 0;
  // Swap-remove from the alive list; loops that remove while iterating run backwards, so the
  // element moved into this position has been visited already.
  const int last = alive_.back();
  alive_[static_cast<std::size_t>(lm.alive_pos)] = last;
  landmarks_[static_cast<std::size_t>(last)].alive_pos = lm.alive_pos;
  alive_.pop_back();
  free_landmarks_.push_back(index);
  --num_landmarks_;
}

void VoEstimator::removeFrame(int frame) {
  const std::uint32_t bits = 3u << maskBit(frame, 0);
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    if (lm.host == frame) {
      removeLandmark(i);
      continue;
    }
    lm.mask &= ~bits;
    if (numObs(lm) < 2) removeLandmark(i);
  }
  Frame& f = frames_[static_cast<std::size_t>(frame)];
  f.active = f.keyframe = f.in_prior = false;
  for (auto& o : f.obs) o.clear();
  prior_H_.middleRows<6>(6 * frame).setZero();
  prior_H_.middleCols<6>(6 * frame).setZero();
  prior_g_.segment<6>(6 * frame).setZero();
}

void VoEstimator::dropNonKeyframes(int keep) {
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const Frame& f = frames_[static_cast<std::size_t>(i)];
    if (f.active && !f.keyframe && i != keep) removeFrame(i);
  }
}

// ---- initialisation and triangulation -----------------------------------------------------------

bool VoEstimator::initialize(const TrackedStereoFrame& frame, const SE3d& T_w_c) {
  const bool pending = pending_reset_;
  const SE3d origin = T_w_c;
  reset();
  pending_reset_ = pending;
  last_good_T_w_c_ = origin;
  previous_T_w_c_ = origin;
  const int slot = allocateFrame(frame, origin);
  Frame& f = frames_[static_cast<std::size_t>(slot)];
  f.keyframe = true;
  f.in_prior = true;
  f.T_w_c_lin = origin;
  // The first pose is fixed by a strong prior (gauge freedom of VO: position and all three rotations).
  prior_H_.block<6, 6>(6 * slot, 6 * slot) = config_.init_pose_weight * Eigen::Matrix<double, 6, 6>::Identity();
  const int created = triangulateNew(slot);
  if (created < config_.min_inliers) {
    reset();
    pending_reset_ = pending;
    last_good_T_w_c_ = origin;
    previous_T_w_c_ = origin;
    return false;
  }
  initialized_ = true;
  frames_since_kf_ = 0;
  return true;
}

int VoEstimator::triangulateNew(int frame) {
  const Frame& f = frames_[static_cast<std::size_t>(frame)];
  const SE3d T_c_w = f.T_w_c.inverse();
  const auto find = [](const std::vector<Observation>& list, std::uint64_t id) -> const Observation* {
    const auto it = std::lower_bound(list.begin(), list.end(), id,
                                     [](const Observation& o, std::uint64_t key) { return o.id < key; });
    return it != list.end() && it->id == id ? &*it : nullptr;
  };
  enum class Outcome { kCreated, kSkipped, kFull };
  // A track seen in this frame's camera ref_cam: triangulated against the view with the widest
  // baseline and stored, like every landmark, as a bearing and inverse distance from this frame's
  // left camera. A right-only track (the frontend's detection_nonoverlap) has no view there to
  // anchor it, so the bearing is a free parameter fixed by its views.
  const auto create = [&](const Observation& o, int ref_cam) {
    if (free_landmarks_.empty()) return Outcome::kFull;
    if (id_to_landmark_.find(o.id) >= 0) return Outcome::kSkipped;
    Eigen::Vector3d b_ref;
    if (!cameras_[static_cast<std::size_t>(ref_cam)].unproject(o.px, b_ref)) return Outcome::kSkipped;
    const SE3d& T_c_ref = T_cam0_cam_[static_cast<std::size_t>(ref_cam)];
    // The other view with the widest baseline: another camera of this frame or any camera of
    // another frame in the window.
    double best_baseline = config_.min_triangulation_dist_m;
    bool found = false;
    SE3d T_c_other;
    Eigen::Vector2d other_px;
    int other_cam = 0;
    for (int g = 0; g < kMaxWindowFrames; ++g) {
      const Frame& fg = frames_[static_cast<std::size_t>(g)];
      if (!fg.active) continue;
      for (int c = 0; c < 2; ++c) {
        if (g == frame && c == ref_cam) continue;
        const Observation* other = find(fg.obs[static_cast<std::size_t>(c)], o.id);
        if (other == nullptr) continue;
        const SE3d T = T_c_w * fg.T_w_c * T_cam0_cam_[static_cast<std::size_t>(c)];
        const double baseline = (T.translation() - T_c_ref.translation()).norm();
        if (baseline >= best_baseline) {
          best_baseline = baseline;
          found = true;
          T_c_other = T;
          other_px = other->px;
          other_cam = c;
        }
      }
    }
    if (!found) return Outcome::kSkipped;
    Eigen::Vector3d b_other;
    if (!cameras_[static_cast<std::size_t>(other_cam)].unproject(other_px, b_other)) return Outcome::kSkipped;
    // Closest points of the rays o_ref + d0 R_ref b_ref and o_other + d1 R_other b_other (least
    // squares in d0, d1), all in this frame's left-camera coordinates.
    const Eigen::Vector3d ray_ref = T_c_ref.so3() * b_ref;
    Eigen::Matrix<double, 3, 2> A;
    A.col(0) = ray_ref;
    A.col(1) = -(T_c_other.so3() * b_other);
    const Eigen::Matrix2d AtA = A.transpose() * A;
    const double det = AtA.determinant();
    if (!(det > 1e-12)) return Outcome::kSkipped;  // parallel rays
    const Eigen::Vector2d d = AtA.inverse() * (A.transpose() * (T_c_other.translation() - T_c_ref.translation()));
    if (!(d(0) > 0.0 && d(1) > 0.0)) return Outcome::kSkipped;
    const Eigen::Vector3d p = T_c_ref.translation() + d(0) * ray_ref;
    const double rho = 1.0 / p.norm();
    if (!(rho >= config_.min_inverse_distance && rho <= config_.max_inverse_distance)) return Outcome::kSkipped;

    const int index = free_landmarks_.back();
    Landmark& lm = landmarks_[static_cast<std::size_t>(index)];
    lm.id = o.id;
    lm.host = frame;
    lm.s = stereographicProject(p);
    lm.rho = rho;
    lm.mask = 0;
    // Every view of this track in the window, each checked against the triangulated point (the
    // left view that defines the bearing is exact by construction).
    for (int g = 0; g < kMaxWindowFrames; ++g) {
      const Frame& fg = frames_[static_cast<std::size_t>(g)];
      if (!fg.active) continue;
      for (int c = 0; c < 2; ++c) {
        const Observation* view = find(fg.obs[static_cast<std::size_t>(c)], o.id);
        if (view == nullptr) continue;
        lm.px[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)] = view->px;
        Eigen::Vector2d r;
        if (g == frame && c == 0) {
          lm.mask |= 1u << maskBit(g, c);
        } else if (residual(lm, g, c, r, nullptr) && r.norm() <= config_.outlier_threshold_px) {
          lm.mask |= 1u << maskBit(g, c);
        }
      }
    }
    if (numObs(lm) < 2) return Outcome::kSkipped;
    if (!id_to_landmark_.insert(lm.id, index)) return Outcome::kFull;
    lm.alive = true;
    lm.alive_pos = static_cast<int>(alive_.size());
    alive_.push_back(index);
    free_landmarks_.pop_back();
    ++num_landmarks_;
    return Outcome::kCreated;
  };
  int created = 0;
  for (const Observation& o : f.obs[0]) {
    const Outcome outcome = create(o, 0);
    if (outcome == Outcome::kFull) return created;
    created += outcome == Outcome::kCreated;
  }
  for (const Observation& o : f.obs[1]) {
    if (find(f.obs[0], o.id) != nullptr) continue;  // seen on the left: that view decides
    const Outcome outcome = create(o, 1);
    if (outcome == Outcome::kFull) return created;
    created += outcome == Outcome::kCreated;
  }
  return created;
}

// ---- single-frame pose step ---------------------------------------------------------------------

void VoEstimator::optimizePose(int frame) {
  const std::uint32_t bits = 3u << maskBit(frame, 0);
  FramePoses poses = framePoses();
  for (int it = 0; it < config_.pose_only_iterations; ++it) {
    poses[static_cast<std::size_t>(frame)].set(frames_[static_cast<std::size_t>(frame)].T_w_c);
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    int count = 0;
    for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
      const int i = alive_[static_cast<std::size_t>(k)];
      const Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
      if (!lm.alive || (lm.mask & bits) == 0) continue;
      for (int c = 0; c < 2; ++c) {
        if ((lm.mask & (1u << maskBit(frame, c))) == 0) continue;
        Eigen::Vector2d r;
        ReprojectionJacobians J;
        if (!residual(poses, lm, frame, c, r, &J)) continue;
        // Huber weights here too (Basalt's pose step ignores them, so one bad track can drag it).
        const double e = r.norm();
        const double w = inv_var_ * (e <= huber_px_ ? 1.0 : huber_px_ / e);
        H.noalias() += w * J.d_target.transpose() * J.d_target;
        b.noalias() += w * J.d_target.transpose() * r;
        ++count;
      }
    }
    if (count < 3) return;
    H.diagonal().array() += 1e-6 * (1.0 + H.diagonal().array());
    const Eigen::Matrix<double, 6, 1> dx = -H.ldlt().solve(b);
    if (!dx.allFinite()) return;
    applyPoseIncrement(frames_[static_cast<std::size_t>(frame)].T_w_c, dx);
    if (dx.norm() < 1e-10) return;
  }
}

int VoEstimator::removeFrameOutliers(int frame, double threshold_px) {
  int removed = 0;
  const std::uint32_t bits = 3u << maskBit(frame, 0);
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive || (lm.mask & bits) == 0 || lm.host == frame) continue;
    for (int c = 0; c < 2; ++c) {
      const std::uint32_t bit = 1u << maskBit(frame, c);
      if ((lm.mask & bit) == 0) continue;
      Eigen::Vector2d r;
      if (!residual(lm, frame, c, r, nullptr) || r.norm() > threshold_px) {
        lm.mask &= ~bit;
        ++removed;
      }
    }
    if (numObs(lm) < 2) removeLandmark(i);
  }
  return removed;
}

bool VoEstimator::isNewKeyframe(int frame) const {
  const Frame& f = frames_[static_cast<std::size_t>(frame)];
  int connected = 0;
  for (const Observation& o : f.obs[0]) {
    const int index = id_to_landmark_.find(o.id);
    if (index >= 0 && (landmarks_[static_cast<std::size_t>(index)].mask & (1u << maskBit(frame, 0))) != 0) ++connected;
  }
  const int total = static_cast<int>(f.obs[0].size());
  // Too few connected points to keep tracking: triangulate now whatever the frame count says.
  if (connected < 2 * config_.min_inliers) return true;
  const double ratio = total > 0 ? static_cast<double>(connected) / total : 0.0;
  return ratio < config_.new_kf_keypoints_thresh && frames_since_kf_ > config_.min_frames_after_kf;
}

// ---- window optimisation ------------------------------------------------------------------------

Eigen::Matrix<double, 6, 1> VoEstimator::priorDelta(int frame) const {
  const Frame& f = frames_[static_cast<std::size_t>(frame)];
  if (!f.active || !f.in_prior) return Eigen::Matrix<double, 6, 1>::Zero();
  return poseDelta(f.T_w_c, f.T_w_c_lin);
}

double VoEstimator::priorCost() const {
  VecH delta = VecH::Zero();
  for (int i = 0; i < kMaxWindowFrames; ++i) delta.segment<6>(6 * i) = priorDelta(i);
  return 0.5 * delta.dot(prior_H_ * delta) + prior_g_.dot(delta) + 0.5 * prior_c_;
}

double VoEstimator::cost() const {
  // An observation that cannot be projected counts like an error of 10x the outlier threshold, so
  // that a step moving points behind a camera is rejected.
  const double invalid_e = 10.0 * config_.outlier_threshold_px;
  const auto huber = [&](double e) { return e <= huber_px_ ? 0.5 * e * e : huber_px_ * (e - 0.5 * huber_px_); };
  const FramePoses poses = framePoses();
  double total = 0.0;
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    const Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1) {
      const int bit = std::countr_zero(m);
      Eigen::Vector2d r;
      const double e = residual(poses, lm, bit / 2, bit % 2, r, nullptr) ? r.norm() : invalid_e;
      total += inv_var_ * huber(e);
    }
  }
  return total + priorCost();
}

void VoEstimator::linearize(MatH& H, VecH& b, const std::vector<int>* only_landmarks, bool full_hessian) {
  H.setZero();
  b.setZero();
  const std::vector<int>& list = only_landmarks != nullptr ? *only_landmarks : alive_;
  const FramePoses poses = framePoses();
  for (const int i : list) {
    const Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    LandmarkLin& L = lin_[static_cast<std::size_t>(i)];
    L.valid = false;
    if (!lm.alive) continue;
    L.H_ll.setZero();
    L.b_l.setZero();
    L.frames = 0;
    const int h = lm.host;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1) {
      const int bit = std::countr_zero(m);
      const int t = bit / 2;
      Eigen::Vector2d r;
      ReprojectionJacobians J;
      if (!residual(poses, lm, t, bit % 2, r, &J)) continue;
      const double e = r.norm();
      const double w = inv_var_ * (e <= huber_px_ ? 1.0 : huber_px_ / e);
      L.H_ll.noalias() += w * J.d_landmark.transpose() * J.d_landmark;
      L.b_l.noalias() += w * J.d_landmark.transpose() * r;
      L.valid = true;
      if (t == h) continue;  // relative pose is the fixed extrinsic: no pose Jacobian
      for (const int f : {h, t}) {
        if ((L.frames & (1u << f)) == 0) {
          L.H_pl[static_cast<std::size_t>(f)].setZero();
          L.frames |= 1u << f;
        }
      }
      const Eigen::Matrix<double, 6, 2> JhW = w * J.d_host.transpose();
      const Eigen::Matrix<double, 6, 2> JtW = w * J.d_target.transpose();
      H.block<6, 6>(6 * h, 6 * h).noalias() += JhW * J.d_host;
      H.block<6, 6>(6 * t, 6 * t).noalias() += JtW * J.d_target;
      // The LM solve reads only the lower triangle (LDLT<Lower>): the block above is skipped there.
      if (full_hessian || h > t) H.block<6, 6>(6 * h, 6 * t).noalias() += JhW * J.d_target;
      if (full_hessian || t > h) H.block<6, 6>(6 * t, 6 * h).noalias() += JtW * J.d_host;
      b.segment<6>(6 * h).noalias() += JhW * r;
      b.segment<6>(6 * t).noalias() += JtW * r;
      L.H_pl[static_cast<std::size_t>(h)].noalias() += JhW * J.d_landmark;
      L.H_pl[static_cast<std::size_t>(t)].noalias() += JtW * J.d_landmark;
    }
  }
  VecH delta = VecH::Zero();
  for (int f = 0; f < kMaxWindowFrames; ++f) delta.segment<6>(6 * f) = priorDelta(f);
  H += prior_H_;
  b.noalias() += prior_H_ * delta;
  b += prior_g_;
}

void VoEstimator::backup() {
  for (Frame& f : frames_) f.T_w_c_backup = f.T_w_c;
  for (const int i : alive_) {
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    lm.s_backup = lm.s;
    lm.rho_backup = lm.rho;
  }
}

void VoEstimator::restore() {
  for (Frame& f : frames_) f.T_w_c = f.T_w_c_backup;
  for (const int i : alive_) {
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    lm.s = lm.s_backup;
    lm.rho = lm.rho_backup;
  }
}

void VoEstimator::applyIncrement(const VecH& dx) {
  for (int f = 0; f < kMaxWindowFrames; ++f) {
    if (frames_[static_cast<std::size_t>(f)].active)
      applyPoseIncrement(frames_[static_cast<std::size_t>(f)].T_w_c, dx.segment<6>(6 * f));
  }
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    const LandmarkLin& L = lin_[static_cast<std::size_t>(i)];
    if (!lm.alive || !L.valid) continue;
    Eigen::Vector3d rhs = L.b_l;
    for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
      const int f = std::countr_zero(m);
      rhs.noalias() += L.H_pl[static_cast<std::size_t>(f)].transpose() * dx.segment<6>(6 * f);
    }
    const Eigen::Vector3d dl = -L.H_ll_inv * rhs;
    lm.s += dl.head<2>();
    lm.rho += dl(2);
  }
}

int VoEstimator::optimize(int max_iterations, bool filter) {
  double lambda = config_.lm_lambda_initial;
  bool filtered = !filter;
  double current = cost();
  int it = 0;
  for (; it < max_iterations; ++it) {
    if (!filtered && it >= config_.filter_iteration) {
      filterOutliers();
      filtered = true;
      current = cost();
    }
    linearize(H_, b_, nullptr, false);
    bool accepted = false;
    bool converged = false;
    for (int attempt = 0; attempt < 8; ++attempt) {
      // Reduced camera system: damp, eliminate every landmark (Schur complement per landmark). Only
      // the lower triangle is formed: the LDLT reads nothing else, so the upper half would be
      // work thrown away.
      H_reduced_ = H_;
      b_reduced_ = b_;
      for (int k = 0; k < kDim; ++k) H_reduced_(k, k) += lambda * std::max(H_(k, k), 1e-6);
      for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
        const int i = alive_[static_cast<std::size_t>(k)];
        LandmarkLin& L = lin_[static_cast<std::size_t>(i)];
        if (!landmarks_[static_cast<std::size_t>(i)].alive || !L.valid) continue;
        Eigen::Matrix3d H_ll = L.H_ll;
        for (int d = 0; d < 3; ++d) H_ll(d, d) += lambda * std::max(L.H_ll(d, d), 1e-6) + kTinyRegularization;
        L.H_ll_inv = H_ll.inverse();
        if (!L.H_ll_inv.allFinite()) {
          L.valid = false;
          continue;
        }
        std::array<Mat63, kMaxWindowFrames> T;
        for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
          const int f = std::countr_zero(m);
          T[static_cast<std::size_t>(f)].noalias() = L.H_pl[static_cast<std::size_t>(f)] * L.H_ll_inv;
          b_reduced_.segment<6>(6 * f).noalias() -= T[static_cast<std::size_t>(f)] * L.b_l;
          // Slots g <= f: the bits of L.frames up to and including f.
          const std::uint32_t lower = L.frames & ((2u << f) - 1u);
          for (std::uint32_t n = lower; n != 0; n &= n - 1) {
            const int g = std::countr_zero(n);
            H_reduced_.block<6, 6>(6 * f, 6 * g).noalias() -=
                T[static_cast<std::size_t>(f)] * L.H_pl[static_cast<std::size_t>(g)].transpose();
          }
        }
      }
      for (int f = 0; f < kMaxWindowFrames; ++f) {
        if (frames_[static_cast<std::size_t>(f)].active) continue;
        H_reduced_.block<6, 6>(6 * f, 6 * f).setIdentity();
        b_reduced_.segment<6>(6 * f).setZero();
      }
      ldlt_.compute(H_reduced_);
      dx_ = ldlt_.solve(-b_reduced_);
      if (dx_.allFinite()) {
        backup();
        applyIncrement(dx_);
        const double next = cost();
        if (std::isfinite(next) && next <= current) {
          accepted = true;
          converged = current - next <= kConvergedRelativeDecrease * current;
          current = next;
          if (config_.use_lm) lambda = std::max(config_.lm_lambda_min, lambda / 3.0);
          break;
        }
        restore();
      }
      if (!config_.use_lm || lambda >= config_.lm_lambda_max) break;
      lambda = std::min(config_.lm_lambda_max, lambda * 10.0);
    }
    if (!accepted || converged) {
      if (!filtered) {
        // Converged before the filter iteration: filter now and optimise the cleaned problem.
        filterOutliers();
        filtered = true;
        current = cost();
        continue;
      }
      ++it;
      break;
    }
  }
  if (!filtered) filterOutliers();
  return it;
}

void VoEstimator::filterOutliers() {
  const FramePoses poses = framePoses();
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    if (!(lm.rho > 0.0 && lm.rho <= 2.0 * config_.max_inverse_distance) || !lm.s.allFinite()) {
      removeLandmark(i);
      continue;
    }
    std::uint32_t outliers = 0;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1) {
      const int bit = std::countr_zero(m);
      Eigen::Vector2d r;
      if (!residual(poses, lm, bit / 2, bit % 2, r, nullptr) || r.norm() > config_.outlier_threshold_px) {
        outliers |= 1u << bit;
      }
    }
    if (outliers == 0) continue;
    const bool host_outlier = (outliers & (1u << maskBit(lm.host, 0))) != 0;
    if (host_outlier || numObs(lm) - std::popcount(outliers) < kFilterMinObservations) {
      removeLandmark(i);
    } else {
      lm.mask &= ~outliers;
    }
  }
}

// ---- marginalisation ----------------------------------------------------------------------------

int VoEstimator::chooseKeyframeToMarginalize(int newest) const {
  // The newest frame and the keyframe before it stay: they carry the current tracks.
  int previous_kf = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const Frame& f = frames_[static_cast<std::size_t>(i)];
    if (!f.active || !f.keyframe || i == newest) continue;
    if (previous_kf < 0 || f.sequence > frames_[static_cast<std::size_t>(previous_kf)].sequence) previous_kf = i;
  }
  std::array<int, kMaxWindowFrames> hosted{}, connected{};
  const std::uint32_t newest_bits = 3u << maskBit(newest, 0);
  for (const int i : alive_) {
    const Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive) continue;
    ++hosted[static_cast<std::size_t>(lm.host)];
    if ((lm.mask & newest_bits) != 0) ++connected[static_cast<std::size_t>(lm.host)];
  }
  int oldest_lost = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const Frame& f = frames_[static_cast<std::size_t>(i)];
    if (!f.active || !f.keyframe || i == newest || i == previous_kf) continue;
    const auto n = static_cast<std::size_t>(i);
    const bool lost = hosted[n] == 0 || static_cast<double>(connected[n]) / hosted[n] < config_.kf_marg_feature_ratio;
    if (lost && (oldest_lost < 0 || f.sequence < frames_[static_cast<std::size_t>(oldest_lost)].sequence))
      oldest_lost = i;
  }
  if (oldest_lost >= 0) return oldest_lost;
  // Otherwise DSO's distance score: drop the keyframe that is close to the others and far from the
  // newest frame, so the window keeps a spread of viewpoints.
  const Eigen::Vector3d p_newest = frames_[static_cast<std::size_t>(newest)].T_w_c.translation();
  int best = -1;
  double best_score = -1.0;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const Frame& f = frames_[static_cast<std::size_t>(i)];
    if (!f.active || !f.keyframe || i == newest || i == previous_kf) continue;
    double sum = 0.0;
    for (int j = 0; j < kMaxWindowFrames; ++j) {
      const Frame& g = frames_[static_cast<std::size_t>(j)];
      if (!g.active || !g.keyframe || j == i || j == newest) continue;
      sum += 1.0 / ((f.T_w_c.translation() - g.T_w_c.translation()).norm() + 1e-5);
    }
    const double score = std::sqrt((f.T_w_c.translation() - p_newest).norm()) * sum;
    if (score > best_score) {
      best_score = score;
      best = i;
    }
  }
  return best;
}

void VoEstimator::prepareMarginalization(int frame) {
  Frame& fm = frames_[static_cast<std::size_t>(frame)];
  // Landmarks hosted here that the newest frame still tracks move to another keyframe that sees
  // them, in its left camera if one does (kept alive, where Basalt loses them); the others are marginalised with
  // the frame, so their information on the window stays in the prior.
  int newest = -1;
  for (int g = 0; g < kMaxWindowFrames; ++g) {
    const Frame& fg = frames_[static_cast<std::size_t>(g)];
    if (fg.active && (newest < 0 || fg.sequence > frames_[static_cast<std::size_t>(newest)].sequence)) newest = g;
  }
  const std::uint32_t newest_bits = 3u << maskBit(newest, 0);
  scratch_landmarks_.clear();
  for (int k = static_cast<int>(alive_.size()) - 1; k >= 0; --k) {
    const int i = alive_[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive || lm.host != frame) continue;
    if (newest == frame || (lm.mask & newest_bits) == 0) {
      scratch_landmarks_.push_back(i);
      continue;
    }
    // The newest keyframe with a left view, else (right-only tracks) with a right view.
    int new_host = -1;
    for (int cam = 0; cam < 2 && new_host < 0; ++cam) {
      for (int g = 0; g < kMaxWindowFrames; ++g) {
        const Frame& fg = frames_[static_cast<std::size_t>(g)];
        if (g == frame || !fg.active || !fg.keyframe || (lm.mask & (1u << maskBit(g, cam))) == 0) continue;
        if (new_host < 0 || fg.sequence > frames_[static_cast<std::size_t>(new_host)].sequence) new_host = g;
      }
    }
    bool moved = false;
    if (new_host >= 0) {
      const SE3d& T_w_h = fm.T_w_c;
      const SE3d& T_w_k = frames_[static_cast<std::size_t>(new_host)].T_w_c;
      // Homogeneous point (bearing, rho) re-expressed in the new host: q = rho * p_k.
      const Eigen::Vector3d q = T_w_k.so3().inverse() * (T_w_h.so3() * stereographicUnproject(lm.s) +
                                                         (T_w_h.translation() - T_w_k.translation()) * lm.rho);
      const double norm = q.norm();
      const double rho = lm.rho / norm;
      if (norm > 0.0 && q.z() > -0.9 * norm && rho > 0.0 && rho <= 2.0 * config_.max_inverse_distance) {
        lm.s = stereographicProject(q);
        lm.rho = rho;
        lm.host = new_host;
        moved = true;
      }
    }
    if (!moved) scratch_landmarks_.push_back(i);
  }
  // Views in this frame of the landmarks that stay cannot go into a pose-only prior: dropped.
  const std::uint32_t bits = 3u << maskBit(frame, 0);
  for (const int i : alive_) {
    Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (lm.alive && lm.host != frame) lm.mask &= ~bits;
  }
}

void VoEstimator::marginalize(int frame) {
  prepareMarginalization(frame);
  // Information on the window from the prior and the marginalised landmarks, landmarks eliminated.
  linearize(H_, b_, &scratch_landmarks_, true);
  for (const int i : scratch_landmarks_) {
    LandmarkLin& L = lin_[static_cast<std::size_t>(i)];
    if (!L.valid) continue;
    const Eigen::Matrix3d H_ll_inv = (L.H_ll + kTinyRegularization * Eigen::Matrix3d::Identity()).inverse();
    if (!H_ll_inv.allFinite()) continue;
    for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
      const int f = std::countr_zero(m);
      const Mat63 T = L.H_pl[static_cast<std::size_t>(f)] * H_ll_inv;
      b_.segment<6>(6 * f).noalias() -= T * L.b_l;
      for (std::uint32_t n = L.frames; n != 0; n &= n - 1) {
        const int g = std::countr_zero(n);
        H_.block<6, 6>(6 * f, 6 * g).noalias() -= T * L.H_pl[static_cast<std::size_t>(g)].transpose();
      }
    }
  }
  // Eliminate the frame's pose.
  const int o = 6 * frame;
  Eigen::Matrix<double, 6, 6> H_mm = H_.block<6, 6>(o, o);
  H_mm.diagonal().array() += kTinyRegularization;
  const Eigen::Matrix<double, 6, 6> H_mm_inv = H_mm.ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
  const Eigen::Matrix<double, kDim, 6> H_xm = H_.middleCols<6>(o);
  const Eigen::Matrix<double, 6, 1> b_m = b_.segment<6>(o);
  H_.noalias() -= H_xm * H_mm_inv * H_xm.transpose();
  b_.noalias() -= H_xm * (H_mm_inv * b_m);
  H_.middleRows<6>(o).setZero();
  H_.middleCols<6>(o).setZero();
  b_.segment<6>(o).setZero();
  H_ = 0.5 * (H_ + H_.transpose()).eval();

  // Remove the frame and the marginalised landmarks.
  for (const int i : scratch_landmarks_) removeLandmark(i);
  removeFrame(frame);

  // Frames the prior now touches get their linearisation point fixed here (first estimates);
  // b_ is the gradient at the current state, so the prior's constant gradient is b - H delta0.
  VecH delta = VecH::Zero();
  for (int f = 0; f < kMaxWindowFrames; ++f) {
    Frame& fr = frames_[static_cast<std::size_t>(f)];
    if (!fr.active) continue;
    if (!fr.in_prior && H_.block<6, 6>(6 * f, 6 * f).diagonal().maxCoeff() > 0.0) {
      fr.in_prior = true;
      fr.T_w_c_lin = fr.T_w_c;
    }
    delta.segment<6>(6 * f) = priorDelta(f);
  }
  const VecH g = b_ - H_ * delta;
  // Square-root form R = Lambda^1/2 V^T, r = Lambda^-1/2 V^T g from the eigendecomposition;
  // negative eigenvalues (round-off) are clipped, so the stored prior is symmetric PSD by construction.
  eigen_.compute(H_);
  const auto& values = eigen_.eigenvalues();
  const auto& vectors = eigen_.eigenvectors();
  const double floor = std::max(values.maxCoeff(), 0.0) * 1e-14;
  VecH lambda_plus = VecH::Zero();
  VecH r = VecH::Zero();
  for (int k = 0; k < kDim; ++k) {
    if (values(k) > floor && values(k) > 0.0) {
      lambda_plus(k) = values(k);
      r(k) = vectors.col(k).dot(g) / std::sqrt(values(k));
    }
  }
  // H = R^T R = V Lambda+ V^T; g = R^T r; c = r^T r.
  prior_H_.noalias() = vectors * lambda_plus.asDiagonal() * vectors.transpose();
  prior_H_ = 0.5 * (prior_H_ + prior_H_.transpose()).eval();
  prior_g_.noalias() = vectors * (lambda_plus.array().sqrt().matrix().asDiagonal() * r);
  prior_c_ = r.squaredNorm();
}

// ---- per frame ----------------------------------------------------------------------------------

void VoEstimator::frameStats(int frame, PoseEstimate& out) const {
  double sum_sq = 0.0, depth = 0.0;
  int inliers = 0, depth_count = 0;
  const std::uint32_t bits = 3u << maskBit(frame, 0);
  for (const int i : alive_) {
    const Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
    if (!lm.alive || (lm.mask & bits) == 0) continue;
    for (int c = 0; c < 2; ++c) {
      if ((lm.mask & (1u << maskBit(frame, c))) == 0) continue;
      Eigen::Vector2d r;
      if (!residual(lm, frame, c, r, nullptr)) continue;
      sum_sq += r.squaredNorm();
      ++inliers;
    }
    if (lm.rho > 0.0) {
      depth += 1.0 / lm.rho;
      ++depth_count;
    }
  }
  out.num_inliers = inliers;
  out.rms_reprojection_px = inliers > 0 ? std::sqrt(sum_sq / inliers) : 0.0;
  out.mean_depth_m = depth_count > 0 ? depth / depth_count : 0.0;
  out.num_keyframes = numKeyframes();
  out.num_landmarks = num_landmarks_;
}

const PoseEstimate& VoEstimator::process(const TrackedStereoFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  PoseEstimate& est = estimate_;
  est = PoseEstimate{};
  est.t_ns = frame.t_ns;
  est.frame_index = frame.frame_index;
  const auto finish = [&](const SE3d& T_w_c) -> const PoseEstimate& {
    est.T_world_cam0 = T_w_c;
    est.T_world_body = T_w_c * T_body_cam0_.inverse();
    est.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return est;
  };
  const auto startOver = [&](FailureReason reason) -> const PoseEstimate& {
    est.failure = reason;
    if (initialize(frame, last_good_T_w_c_)) {
      est.state = pending_reset_ ? TrackingState::kReset : TrackingState::kTracking;
      pending_reset_ = false;
      est.keyframe = true;
      int slot = 0;
      for (int i = 0; i < kMaxWindowFrames; ++i) {
        if (frames_[static_cast<std::size_t>(i)].active) slot = i;
      }
      frameStats(slot, est);
      est.new_landmarks = num_landmarks_;
    } else {
      est.state = TrackingState::kLost;
      est.failure = reason == FailureReason::kNone ? FailureReason::kTooFewStereoPoints : reason;
    }
    velocity_ = SE3d();
    previous_T_w_c_ = last_good_T_w_c_;
    return finish(last_good_T_w_c_);
  };

  if (!initialized_) return startOver(FailureReason::kNone);

  ++frames_since_kf_;
  dropNonKeyframes(-1);
  // Frames skipped before this one (dropped or damaged): the constant-velocity guess and the motion
  // bounds span all the intervals since the previous frame.
  const int intervals = 1 + std::max(0, frame.frames_missing_before);
  const SE3d predicted =
      previous_T_w_c_ * (intervals == 1 ? velocity_ : SE3d::exp(velocity_.log() * static_cast<double>(intervals)));
  const int n = allocateFrame(frame, predicted);
  attachObservations(n);
  optimizePose(n);
  est.num_outliers = removeFrameOutliers(n, config_.outlier_threshold_px);

  const auto fail = [&](FailureReason reason) -> const PoseEstimate& {
    pending_reset_ = true;
    return startOver(reason);
  };
  const auto countInliers = [&] {
    int count = 0;
    const std::uint32_t bits = 3u << maskBit(n, 0);
    for (const int i : alive_) {
      const Landmark& lm = landmarks_[static_cast<std::size_t>(i)];
      if (lm.alive) count += std::popcount(lm.mask & bits);
    }
    return count;
  };
  if (countInliers() < config_.min_inliers) return fail(FailureReason::kTooFewInliers);

  est.keyframe = isNewKeyframe(n);
  if (est.keyframe) {
    frames_[static_cast<std::size_t>(n)].keyframe = true;
    frames_since_kf_ = 0;
    est.new_landmarks = triangulateNew(n);
  }
  est.lm_iterations = optimize(config_.max_iterations, true);

  frameStats(n, est);
  const SE3d& T_w_c = frames_[static_cast<std::size_t>(n)].T_w_c;
  const SE3d step = previous_T_w_c_.inverse() * T_w_c;
  if (!T_w_c.translation().allFinite() || !T_w_c.unitQuaternion().coeffs().allFinite()) {
    return fail(FailureReason::kExplodingCost);
  }
  if (est.num_inliers < config_.min_inliers) return fail(FailureReason::kTooFewInliers);
  if (est.rms_reprojection_px > config_.max_rms_reprojection_px) return fail(FailureReason::kExplodingCost);
  if (step.translation().norm() > config_.max_translation_per_frame_m * intervals ||
      step.so3().angle() > config_.max_rotation_per_frame_deg * M_PI / 180.0 * intervals) {
    return fail(FailureReason::kImpossibleMotion);
  }

  if (est.keyframe) {
    while (numKeyframes() > config_.max_keyframes) {
      const int m = chooseKeyframeToMarginalize(n);
      if (m < 0) break;
      marginalize(m);
    }
    est.num_keyframes = numKeyframes();
    est.num_landmarks = num_landmarks_;
  }
  est.state = TrackingState::kTracking;
  velocity_ = intervals == 1 ? step : SE3d::exp(step.log() / static_cast<double>(intervals));
  previous_T_w_c_ = T_w_c;
  last_good_T_w_c_ = T_w_c;
  return finish(T_w_c);
}

// ---- inspection ---------------------------------------------------------------------------------

std::vector<std::pair<std::int64_t, SE3d>> VoEstimator::windowPoses() const {
  std::vector<int> order;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    if (frames_[static_cast<std::size_t>(i)].active) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return frames_[static_cast<std::size_t>(a)].sequence < frames_[static_cast<std::size_t>(b)].sequence;
  });
  std::vector<std::pair<std::int64_t, SE3d>> poses;
  for (int i : order)
    poses.emplace_back(frames_[static_cast<std::size_t>(i)].t_ns, frames_[static_cast<std::size_t>(i)].T_w_c);
  return poses;
}

Eigen::MatrixXd VoEstimator::priorHessian() const {
  std::vector<int> order;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    if (frames_[static_cast<std::size_t>(i)].active) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return frames_[static_cast<std::size_t>(a)].sequence < frames_[static_cast<std::size_t>(b)].sequence;
  });
  const int n = static_cast<int>(order.size());
  Eigen::MatrixXd H(6 * n, 6 * n);
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      H.block<6, 6>(6 * a, 6 * b) =
          prior_H_.block<6, 6>(6 * order[static_cast<std::size_t>(a)], 6 * order[static_cast<std::size_t>(b)]);
    }
  }
  return H;
}

double VoEstimator::optimizeWindow(int iterations) {
  if (initialized_) optimize(iterations, false);
  return cost();
}

int VoEstimator::oldestKeyframe() const {
  int oldest = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const Frame& f = frames_[static_cast<std::size_t>(i)];
    if (f.active && f.keyframe && (oldest < 0 || f.sequence < frames_[static_cast<std::size_t>(oldest)].sequence)) {
      oldest = i;
    }
  }
  return numKeyframes() < 2 ? -1 : oldest;
}

bool VoEstimator::dropViewsOfOldestKeyframe() {
  const int oldest = oldestKeyframe();
  if (oldest < 0) return false;
  prepareMarginalization(oldest);
  return true;
}

bool VoEstimator::marginalizeOldestKeyframe() {
  const int oldest = oldestKeyframe();
  if (oldest < 0) return false;
  marginalize(oldest);
  return true;
}

}  // namespace voca
