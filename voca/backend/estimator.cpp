#include "voca/backend/estimator.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>

#include "voca/backend/triangulation.h"
#include "voca/core/error.h"

namespace voca {

using backend::frameBits;
using backend::Landmark;
using backend::maskBit;
using backend::Observation;
using backend::WindowFrame;

namespace {

// The optimiser, which owns the config and the measurement model, built after the inputs are checked.
backend::WindowOptimizer checkedOptimizer(const BackendConfig& config, const StereoRig& rig) {
  validateBackendConfig(config, "backend");
  rig.requireStereo();
  return backend::WindowOptimizer(config,
                                  backend::StereoResiduals(rig, config.obs_std_dev_px, config.obs_huber_thresh_px));
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

std::string_view untrackedCause(const PoseEstimate& estimate) {
  if (estimate.failure == FailureReason::kNone && estimate.state == TrackingState::kReset) {
    return "started again after lost frames";
  }
  return failureReasonName(estimate.failure);
}

VoEstimator::VoEstimator(const BackendConfig& config, const StereoRig& rig)
    : optimizer_(checkedOptimizer(config, rig)),
      T_body_cam0_(rig.cameras[0].T_body_cam),
      window_(config.max_observations_per_camera),
      landmarks_(config.max_landmarks) {
  scratch_landmarks_.reserve(static_cast<std::size_t>(config.max_landmarks));
  frame_verdicts_.resize(static_cast<std::size_t>(config.max_landmarks));
  reset();
}

void VoEstimator::reset() {
  window_.clear();
  landmarks_.clear();
  prior_.clear();
  initialized_ = false;
  pending_reset_ = false;
  previous_T_w_c_ = T_body_cam0_;  // the body starts at the world origin
  velocity_ = SE3d();
  frames_since_kf_ = 0;
}

// ---- frames -------------------------------------------------------------------------------------

void VoEstimator::removeFrame(int frame) {
  landmarks_.dropFrame(frame);
  window_.release(frame);
  prior_.removeFrame(frame);
}

void VoEstimator::dropNonKeyframes(int keep) {
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const WindowFrame& f = window_[i];
    if (f.active && !f.keyframe && i != keep) removeFrame(i);
  }
}

bool VoEstimator::initialize(const TrackedStereoFrame& frame, const SE3d& T_w_c) {
  const bool pending = pending_reset_;
  const SE3d origin = T_w_c;
  reset();
  pending_reset_ = pending;
  previous_T_w_c_ = origin;
  const int slot = window_.add(frame, origin);
  WindowFrame& f = window_[slot];
  f.keyframe = true;
  f.in_prior = true;
  f.T_w_c_lin = origin;
  // The first pose is fixed by a strong prior (gauge freedom of VO: position and all three rotations).
  prior_.fixPose(slot, config().init_pose_weight);
  const int created = backend::triangulateNewLandmarks(slot, window_, landmarks_, model(), config());
  if (created < config().min_inliers) {
    reset();
    pending_reset_ = pending;
    previous_T_w_c_ = origin;
    return false;
  }
  initialized_ = true;
  frames_since_kf_ = 0;
  return true;
}

int VoEstimator::removeFrameOutliers(int frame) {
  constexpr std::uint8_t kJudged = 16;
  const std::uint32_t bits = frameBits(frame);
  const backend::WindowPoses poses = model().windowPoses(window_);
  const std::vector<int>& alive = landmarks_.alive();
  int judged = 0, beyond = 0;
  for (std::size_t k = 0; k < alive.size(); ++k) {
    std::uint8_t& verdict = frame_verdicts_[k];
    verdict = 0;
    const Landmark& lm = landmarks_[alive[k]];
    if (!lm.alive || (lm.mask & bits) == 0 || lm.host == frame) continue;
    verdict = kJudged;
    const HostBearing bearing(poses[static_cast<std::size_t>(lm.host)].T_w_c0, lm.s, false);
    for (int c = 0; c < 2; ++c) {
      if ((lm.mask & (1u << maskBit(frame, c))) == 0) continue;
      ++judged;
      Eigen::Vector2d r;
      if (!model().residual(poses, bearing, lm, frame, c, r, nullptr)) {
        verdict |= static_cast<std::uint8_t>(1u << c);
      } else if (r.norm() > config().outlier_threshold_px) {
        verdict |= static_cast<std::uint8_t>(4u << c);
        ++beyond;
      }
    }
  }
  // Unprojectable views go always; views beyond the threshold only while they are the minority.
  const std::uint8_t removable = beyond > config().max_frame_outlier_share * judged ? 3u : 15u;
  int removed = 0;
  // Removing a landmark moves the last one of alive() to its position, one already visited.
  for (std::size_t k = alive.size(); k-- > 0;) {
    if ((frame_verdicts_[k] & kJudged) == 0) continue;
    const std::uint8_t verdict = frame_verdicts_[k] & removable;
    const int i = alive[k];
    Landmark& lm = landmarks_[i];
    for (int c = 0; c < 2; ++c) {
      if ((verdict & (5u << c)) == 0) continue;
      lm.mask &= ~(1u << maskBit(frame, c));
      ++removed;
    }
    if (lm.numObs() < 2) landmarks_.remove(i);
  }
  return removed;
}

bool VoEstimator::isNewKeyframe(int frame) const {
  const WindowFrame& f = window_[frame];
  int connected = 0;
  for (const Observation& o : f.obs[0]) {
    const int index = landmarks_.find(o.id);
    if (index >= 0 && (landmarks_[index].mask & (1u << maskBit(frame, 0))) != 0) ++connected;
  }
  const int total = static_cast<int>(f.obs[0].size());
  // Too few connected points to keep tracking: triangulate now whatever the frame count says.
  if (connected < 2 * config().min_inliers) return true;
  const double ratio = total > 0 ? static_cast<double>(connected) / total : 0.0;
  if (config().max_frames_after_kf > 0 && frames_since_kf_ >= config().max_frames_after_kf) return true;
  return ratio < config().new_kf_keypoints_thresh && frames_since_kf_ > config().min_frames_after_kf;
}

// ---- marginalisation ----------------------------------------------------------------------------

int VoEstimator::chooseKeyframeToMarginalize(int newest) const {
  // The newest frame and the keyframe before it stay: they carry the current tracks.
  int previous_kf = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const WindowFrame& f = window_[i];
    if (!f.active || !f.keyframe || i == newest) continue;
    if (previous_kf < 0 || f.sequence > window_[previous_kf].sequence) previous_kf = i;
  }
  std::array<int, kMaxWindowFrames> hosted{}, connected{};
  const std::uint32_t newest_bits = frameBits(newest);
  for (const int i : landmarks_.alive()) {
    const Landmark& lm = landmarks_[i];
    if (!lm.alive) continue;
    ++hosted[static_cast<std::size_t>(lm.host)];
    if ((lm.mask & newest_bits) != 0) ++connected[static_cast<std::size_t>(lm.host)];
  }
  int oldest_lost = -1;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const WindowFrame& f = window_[i];
    if (!f.active || !f.keyframe || i == newest || i == previous_kf) continue;
    const auto n = static_cast<std::size_t>(i);
    const bool lost = hosted[n] == 0 || static_cast<double>(connected[n]) / hosted[n] < config().kf_marg_feature_ratio;
    if (lost && (oldest_lost < 0 || f.sequence < window_[oldest_lost].sequence)) oldest_lost = i;
  }
  if (oldest_lost >= 0) return oldest_lost;
  // Otherwise DSO's distance score: drop the keyframe that is close to the others and far from the
  // newest frame, so the window keeps a spread of viewpoints.
  const Eigen::Vector3d p_newest = window_[newest].T_w_c.translation();
  int best = -1;
  double best_score = -1.0;
  for (int i = 0; i < kMaxWindowFrames; ++i) {
    const WindowFrame& f = window_[i];
    if (!f.active || !f.keyframe || i == newest || i == previous_kf) continue;
    double sum = 0.0;
    for (int j = 0; j < kMaxWindowFrames; ++j) {
      const WindowFrame& g = window_[j];
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
  WindowFrame& fm = window_[frame];
  // Landmarks hosted here are marginalised with the frame, so their information on the window stays
  // in the prior. With rehost_landmarks, those the newest frame still tracks move instead to another
  // keyframe that sees them, in its left camera if one does (kept alive, but their views here are lost).
  const int newest = window_.newest();
  const std::uint32_t newest_bits = frameBits(newest);
  scratch_landmarks_.clear();
  for (int k = static_cast<int>(landmarks_.alive().size()) - 1; k >= 0; --k) {
    const int i = landmarks_.alive()[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks_[i];
    if (!lm.alive || lm.host != frame) continue;
    if (!config().rehost_landmarks || newest == frame || (lm.mask & newest_bits) == 0) {
      scratch_landmarks_.push_back(i);
      continue;
    }
    // The newest keyframe with a left view, else (right-only tracks) with a right view.
    int new_host = -1;
    for (int cam = 0; cam < 2 && new_host < 0; ++cam) {
      for (int g = 0; g < kMaxWindowFrames; ++g) {
        const WindowFrame& fg = window_[g];
        if (g == frame || !fg.active || !fg.keyframe || (lm.mask & (1u << maskBit(g, cam))) == 0) continue;
        if (new_host < 0 || fg.sequence > window_[new_host].sequence) new_host = g;
      }
    }
    bool moved = false;
    if (new_host >= 0) {
      const SE3d& T_w_h = fm.T_w_c;
      const SE3d& T_w_k = window_[new_host].T_w_c;
      // Homogeneous point (bearing, rho) re-expressed in the new host: q = rho * p_k.
      const Eigen::Vector3d q = T_w_k.so3().inverse() * (T_w_h.so3() * stereographicUnproject(lm.s) +
                                                         (T_w_h.translation() - T_w_k.translation()) * lm.rho);
      const double norm = q.norm();
      const double rho = lm.rho / norm;
      if (norm > 0.0 && q.z() > -0.9 * norm && rho > 0.0 && rho <= 2.0 * config().max_inverse_distance) {
        lm.s = stereographicProject(q);
        lm.rho = rho;
        lm.host = new_host;
        moved = true;
      }
    }
    if (!moved) scratch_landmarks_.push_back(i);
  }
  // Views in this frame of the landmarks that stay cannot go into a pose-only prior: dropped.
  const std::uint32_t bits = frameBits(frame);
  for (const int i : landmarks_.alive()) {
    Landmark& lm = landmarks_[i];
    if (lm.alive && lm.host != frame) lm.mask &= ~bits;
  }
}

void VoEstimator::marginalize(int frame) {
  prepareMarginalization(frame);
  optimizer_.linearizeForMarginalization(state(), scratch_landmarks_);
  backend::MarginalizationPrior::eliminatePose(optimizer_.hessian(), optimizer_.gradient(), frame);
  // Remove the frame and the marginalised landmarks.
  for (const int i : scratch_landmarks_) landmarks_.remove(i);
  removeFrame(frame);
  prior_.replace(window_, optimizer_.hessian(), optimizer_.gradient());
}

// ---- per frame ----------------------------------------------------------------------------------

void VoEstimator::frameStats(int frame, PoseEstimate& out) const {
  double sum_sq = 0.0, depth = 0.0;
  int inliers = 0, depth_count = 0;
  const std::uint32_t bits = frameBits(frame);
  const backend::WindowPoses poses = model().windowPoses(window_);
  for (const int i : landmarks_.alive()) {
    const Landmark& lm = landmarks_[i];
    if (!lm.alive || (lm.mask & bits) == 0) continue;
    const HostBearing bearing(poses[static_cast<std::size_t>(lm.host)].T_w_c0, lm.s, false);
    for (int c = 0; c < 2; ++c) {
      if ((lm.mask & (1u << maskBit(frame, c))) == 0) continue;
      Eigen::Vector2d r;
      if (!model().residual(poses, bearing, lm, frame, c, r, nullptr)) continue;
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
  out.num_keyframes = window_.numKeyframes();
  out.num_landmarks = landmarks_.size();
}

std::size_t VoEstimator::worldLandmarks(std::span<Eigen::Vector3f> out) const {
  std::size_t n = 0;
  for (const int index : landmarks_.alive()) {
    if (n == out.size()) break;
    const backend::Landmark& lm = landmarks_[index];
    if (!(lm.rho > 0.0) || lm.host < 0) continue;
    const SE3d& T_w_host = window_[lm.host].T_w_c;
    out[n++] = (T_w_host * (stereographicUnproject(lm.s) / lm.rho)).cast<float>();
  }
  return n;
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
    if (initialize(frame, previous_T_w_c_)) {
      est.state = pending_reset_ ? TrackingState::kReset : TrackingState::kTracking;
      pending_reset_ = false;
      est.keyframe = true;
      int slot = 0;
      for (int i = 0; i < kMaxWindowFrames; ++i) {
        if (window_[i].active) slot = i;
      }
      frameStats(slot, est);
      est.new_landmarks = landmarks_.size();
    } else {
      est.state = TrackingState::kLost;
      est.failure = reason == FailureReason::kNone ? FailureReason::kTooFewStereoPoints : reason;
    }
    velocity_ = SE3d();
    return finish(previous_T_w_c_);
  };

  if (!initialized_) return startOver(FailureReason::kNone);

  ++frames_since_kf_;
  dropNonKeyframes(-1);
  // Frames skipped before this one (dropped or damaged): the constant-velocity guess and the motion
  // bounds span all the intervals since the previous frame.
  const int intervals = 1 + std::max(0, frame.frames_missing_before);
  const SE3d predicted =
      previous_T_w_c_ * (intervals == 1 ? velocity_ : SE3d::exp(velocity_.log() * static_cast<double>(intervals)));
  const int n = window_.add(frame, predicted);
  landmarks_.attach(window_, n);
  est.pose_iterations = optimizer_.optimizePose(state(), n);
  est.num_outliers = removeFrameOutliers(n);

  const auto fail = [&](FailureReason reason) -> const PoseEstimate& {
    pending_reset_ = true;
    return startOver(reason);
  };
  const auto countInliers = [&] {
    int count = 0;
    const std::uint32_t bits = frameBits(n);
    for (const int i : landmarks_.alive()) {
      const Landmark& lm = landmarks_[i];
      if (lm.alive) count += std::popcount(lm.mask & bits);
    }
    return count;
  };
  if (countInliers() < config().min_inliers) return fail(FailureReason::kTooFewInliers);

  est.keyframe = isNewKeyframe(n);
  if (est.keyframe) {
    window_[n].keyframe = true;
    frames_since_kf_ = 0;
    est.new_landmarks = backend::triangulateNewLandmarks(n, window_, landmarks_, model(), config());
  }
  est.lm_iterations = optimizer_.optimize(state(), config().max_iterations, true);
  est.lm_linearizations = optimizer_.linearizations();
  est.lm_cost_passes = optimizer_.costPasses();

  frameStats(n, est);
  const SE3d& T_w_c = window_[n].T_w_c;
  const SE3d step = previous_T_w_c_.inverse() * T_w_c;
  if (!T_w_c.translation().allFinite() || !T_w_c.unitQuaternion().coeffs().allFinite()) {
    return fail(FailureReason::kExplodingCost);
  }
  if (est.num_inliers < config().min_inliers) return fail(FailureReason::kTooFewInliers);
  if (est.rms_reprojection_px > config().max_rms_reprojection_px) return fail(FailureReason::kExplodingCost);
  if (step.translation().norm() > config().max_translation_per_frame_m * intervals ||
      step.so3().angle() > config().max_rotation_per_frame_deg * M_PI / 180.0 * intervals) {
    return fail(FailureReason::kImpossibleMotion);
  }

  if (est.keyframe) {
    while (window_.numKeyframes() > config().max_keyframes) {
      const int m = chooseKeyframeToMarginalize(n);
      if (m < 0) break;
      marginalize(m);
    }
    est.num_keyframes = window_.numKeyframes();
    est.num_landmarks = landmarks_.size();
  }
  est.state = TrackingState::kTracking;
  velocity_ = intervals == 1 ? step : SE3d::exp(step.log() / static_cast<double>(intervals));
  previous_T_w_c_ = T_w_c;
  return finish(T_w_c);
}

// ---- inspection ---------------------------------------------------------------------------------

std::vector<std::pair<std::int64_t, SE3d>> VoEstimator::windowPoses() const {
  std::vector<std::pair<std::int64_t, SE3d>> poses;
  for (int i : window_.orderedSlots()) poses.emplace_back(window_[i].t_ns, window_[i].T_w_c);
  return poses;
}

Eigen::MatrixXd VoEstimator::priorHessian() const {
  const std::vector<int> order = window_.orderedSlots();
  const int n = static_cast<int>(order.size());
  Eigen::MatrixXd H(6 * n, 6 * n);
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      H.block<6, 6>(6 * a, 6 * b) =
          prior_.hessian().block<6, 6>(6 * order[static_cast<std::size_t>(a)], 6 * order[static_cast<std::size_t>(b)]);
    }
  }
  return H;
}

double VoEstimator::optimizeWindow(int iterations) {
  if (initialized_) optimizer_.optimize(state(), iterations, false);
  return optimizer_.cost(state());
}

int VoEstimator::filterWindowOutliers(bool from_cost_pass) {
  std::vector<std::uint32_t> outliers(landmarks_.alive().size());
  if (from_cost_pass) optimizer_.cost(state(), outliers.data());
  optimizer_.filterOutliers(state(), from_cost_pass ? outliers.data() : nullptr);
  int observations = 0;
  for (const int i : landmarks_.alive()) observations += landmarks_[i].numObs();
  return observations;
}

double VoEstimator::linearizedWindowCost() { return initialized_ ? optimizer_.linearizedCost(state()) : 0.0; }

bool VoEstimator::dropViewsOfOldestKeyframe() {
  const int oldest = window_.oldestKeyframe();
  if (oldest < 0) return false;
  prepareMarginalization(oldest);
  return true;
}

bool VoEstimator::marginalizeOldestKeyframe() {
  const int oldest = window_.oldestKeyframe();
  if (oldest < 0) return false;
  marginalize(oldest);
  return true;
}

}  // namespace voca
