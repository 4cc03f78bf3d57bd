#include "voca/frontend/frontend.h"

#include <fmt/core.h>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "voca/core/error.h"
#include "voca/geometry/so3.h"

namespace voca {

void FrontendStats::reserve(std::size_t max_points) {
  guess_dist_plain_px.reserve(2 * max_points);
  guess_dist_prior_px.reserve(2 * max_points);
}

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

void FrontendStats::clear() {
  temporal = {};
  bridged = {false, false};
  detected = detected_right_only = stereo_matched = stereo_rematched = epipolar_rejected = thinned = num_left =
      num_right = 0;
  guess_dist_plain_px.clear();
  guess_dist_prior_px.clear();
  time_ms = 0.0;
}

namespace {

// How far from a point's previous position its patches are fetched ahead (level-0 pixels): most
// tracks move less than this per frame.
constexpr float kPrefetchMarginPx = 2.f;

// Asks the memory system for the templates' bytes without waiting for them. A speed hint only.
void prefetchTemplates(std::span<const PatchTemplate> templates) {
  constexpr std::size_t kLineBytes = 64;  // a typical cache line
  const auto* bytes = reinterpret_cast<const char*>(templates.data());
  for (std::size_t offset = 0; offset < templates.size_bytes(); offset += kLineBytes)
    __builtin_prefetch(bytes + offset);
}

// The centre of the detection mask (image_safe_radius_px): every camera model starts fx fy cx cy.
Eigen::Vector2f principalPoint(const CameraCalibration& camera) {
  const std::vector<double> intrinsics = camera.camera.params();
  return {static_cast<float>(intrinsics[2]), static_cast<float>(intrinsics[3])};
}

}  // namespace

KltFrontend::KltFrontend(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities)
    : config_(config) {
  validateFrontendConfig(config_);
  if (rig.cameras.size() < 2) {
    throw InputError(
        fmt::format("{}: the frontend needs a stereo calibration (2 cameras), got {}", rig.source, rig.cameras.size()));
  }
  pattern_ = patternBySize(config_.pattern);
  num_levels_ = config_.pyramid_levels + 1;
  prior_levels_ = config_.prior_pyramid_levels < 0 ? num_levels_ : config_.prior_pyramid_levels + 1;
  backward_levels_ = config_.backward_pyramid_levels < 0 ? num_levels_ : config_.backward_pyramid_levels + 1;
  temporal_round_trip2_ = static_cast<float>(config_.max_recovered_dist2_px2);
  stereo_round_trip2_ = static_cast<float>(config_.stereoRoundTripDist2());
  align_.max_iterations = config_.max_iterations;
  align_.min_step_px = static_cast<float>(config_.min_step_px);
  align_.coarse_min_step_px = static_cast<float>(config_.coarse_min_step_px);
  align_.skip_coarse_outside = config_.skip_coarse_outside;
  max_points_ = capacities.max_points;
  if (max_points_ < 1 || max_points_ > FrontendCapacities::kMaxPointsBound) {
    throw InputError(fmt::format("frontend capacity: max_points {} must be between 1 and {}", max_points_,
                                 FrontendCapacities::kMaxPointsBound));
  }
  width_ = rig.cameras[0].width;
  height_ = rig.cameras[0].height;
  const int max_width = std::max({capacities.max_width, rig.cameras[0].width, rig.cameras[1].width});
  const int max_height = std::max({capacities.max_height, rig.cameras[0].height, rig.cameras[1].height});
  if (max_width <= 0 || max_height <= 0) throw InputError("frontend capacity: unknown image size");

  for (int c = 0; c < 2; ++c) {
    cameras_model_[static_cast<std::size_t>(c)] = rig.cameras[static_cast<std::size_t>(c)].camera;
    CameraState& cam = cameras_[static_cast<std::size_t>(c)];
    for (ImagePyramid& pyramid : cam.pyramids)
      pyramid = ImagePyramid(max_width, max_height, num_levels_, config_.presmooth != InputScope::kOff);
    cam.ids.reserve(static_cast<std::size_t>(max_points_));
    cam.points.reserve(static_cast<std::size_t>(max_points_));
    cam.slots.reserve(static_cast<std::size_t>(max_points_));
    for (TemporalPart& part : cam.parts) part.reserve(static_cast<std::size_t>(max_points_));
    cam.step.reserve(static_cast<std::size_t>(max_points_));
    // Live points plus the scratch slots of each share of the temporal step.
    const int slot_count = max_points_ + kScratchSlots * static_cast<int>(cam.parts.size());
    cam.num_levels = num_levels_;
    cam.pool.resize(static_cast<std::size_t>(slot_count) * static_cast<std::size_t>(num_levels_));
    cam.free_slots.reserve(static_cast<std::size_t>(slot_count));
    cam.built_levels.assign(static_cast<std::size_t>(slot_count), 0);
    cam.resetSlots();
    cam.bridge = IFrameBridge(max_width, max_height, config_.bridge_iframes, config_.prior_reject_inconsistent);
    // The constructor sizes every level to the capacity: the largest coarsest level the search sees.
    const FloatView coarsest = cam.pyramids[0].level(num_levels_ - 1);
    cam.shift_search = ImageShiftSearch(coarsest.width, coarsest.height);
  }
  const SE3d T_cam0_cam1 = rig.T_cam0_cam1();
  T_cam1_cam0_ = T_cam0_cam1.inverse();
  // f0 ~ R f1 + t up to depth; f0 . (t x R f1) = 0. t normalised so the threshold is scale-free.
  const Eigen::Vector3d t = T_cam0_cam1.translation();
  essential_ = SO3d::hat(t.norm() > 0.0 ? Eigen::Vector3d(t.normalized()) : t) * T_cam0_cam1.rotationMatrix();
  average_depth_m_ = config_.matching_default_depth_m;
  if (config_.thin_when_full_px > 0.0) {
    thin_cell_px_ = static_cast<float>(config_.thin_when_full_px / 2.0);
    thin_cols_ = static_cast<int>(std::ceil(static_cast<float>(max_width) / thin_cell_px_)) + 1;
    thin_rows_ = static_cast<int>(std::ceil(static_cast<float>(max_height) / thin_cell_px_)) + 1;
    thin_grid_.assign(static_cast<std::size_t>(thin_cols_) * static_cast<std::size_t>(thin_rows_), -1);
    thinned_ids_.reserve(static_cast<std::size_t>(max_points_));
  }

  detector_params_.grid_size_px = config_.grid_size_px;
  detector_params_.max_threshold = config_.detection_max_threshold;
  detector_params_.min_threshold = config_.detection_min_threshold;
  detector_params_.border_px = config_.detection_border_px;
  detector_params_.safe_radius_px = static_cast<float>(config_.image_safe_radius_px);
  detector_params_.safe_center = principalPoint(rig.cameras[0]);
  detector_ = GridDetector(max_width, max_height, config_.grid_size_px);
  new_points_.reserve(static_cast<std::size_t>(max_points_));
  if (config_.stereo_rematch) {
    for (auto* v : {&rematch_ids_, &merged_ids_}) v->reserve(static_cast<std::size_t>(max_points_));
    for (auto* v : {&rematch_points_, &merged_points_}) v->reserve(static_cast<std::size_t>(max_points_));
    for (auto* v : {&rematch_slots_, &merged_slots_}) v->reserve(static_cast<std::size_t>(max_points_));
  }
  right_detector_params_ = detector_params_;
  right_detector_params_.safe_center = principalPoint(rig.cameras[1]);
  if (config_.detection_nonoverlap) computeRightOverlap(rig);
}

void KltFrontend::computeRightOverlap(const StereoRig& rig) {
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
          if (!cameras_model_[1].unproject(Eigen::Vector2d(u, v), bearing)) continue;
          if (!cameras_model_[0].project(T_cam0_cam1 * (bearing * depth), uv)) continue;
          seen = uv.x() >= border && uv.y() >= border && uv.x() < rig.cameras[0].width - border &&
                 uv.y() < rig.cameras[0].height - border;
        }
      }
      right_overlap_[static_cast<std::size_t>(cy * cells_x + cx)] = seen ? 1 : 0;
    }
  }
}

void KltFrontend::TemporalPart::reserve(std::size_t max_points) {
  ids.reserve(max_points);
  points.reserve(max_points);
  slots.reserve(max_points);
  traces.reserve(max_points);
  retry_candidates.reserve(max_points);
  for (auto* v : {&flow_x, &flow_y, &guess_dist_plain_px, &guess_dist_prior_px}) v->reserve(max_points);
  free_slots.reserve(max_points + kScratchSlots);
}

void KltFrontend::TemporalPart::clear() {
  stats = {};
  ids.clear();
  points.clear();
  slots.clear();
  traces.clear();
  retry_candidates.clear();
  for (auto* v : {&flow_x, &flow_y, &guess_dist_plain_px, &guess_dist_prior_px}) v->clear();
}

void KltFrontend::TemporalPart::append(const TemporalPart& other) {
  for (RetryCandidate candidate : other.retry_candidates) {
    candidate.next += ids.size();
    candidate.trace += traces.size();
    retry_candidates.push_back(candidate);
  }
  stats += other.stats;
  ids.insert(ids.end(), other.ids.begin(), other.ids.end());
  points.insert(points.end(), other.points.begin(), other.points.end());
  slots.insert(slots.end(), other.slots.begin(), other.slots.end());
  traces.insert(traces.end(), other.traces.begin(), other.traces.end());
  flow_x.insert(flow_x.end(), other.flow_x.begin(), other.flow_x.end());
  flow_y.insert(flow_y.end(), other.flow_y.begin(), other.flow_y.end());
  guess_dist_plain_px.insert(guess_dist_plain_px.end(), other.guess_dist_plain_px.begin(),
                             other.guess_dist_plain_px.end());
  guess_dist_prior_px.insert(guess_dist_prior_px.end(), other.guess_dist_prior_px.begin(),
                             other.guess_dist_prior_px.end());
}

void KltFrontend::CameraState::resetSlots() {
  free_slots.clear();
  for (TemporalPart& part : parts) part.free_slots.clear();  // a step cut short may have left scratch slots there
  const int count = static_cast<int>(pool.size()) / num_levels;
  for (int i = count - 1; i >= 0; --i) free_slots.push_back(i);
  slots.clear();
}

void KltFrontend::reset() {
  for (CameraState& cam : cameras_) {
    cam.ids.clear();
    cam.points.clear();
    cam.resetSlots();
    cam.step.clear();
    cam.bridge.clear();
    cam.previous_flow.setZero();
    cam.flow_known = false;
  }
  have_previous_ = false;
}

bool KltFrontend::trackForward(std::span<const PatchTemplate> forward, const ImagePyramid& to, const Eigen::Vector2f& p,
                               const Eigen::Vector2f& flow_guess, int levels, Eigen::Vector2f& tracked,
                               Eigen::Vector2f& fine_start) const {
  SE2f T_forward(0.f, p + flow_guess);
  const std::span<const PatchTemplate> used = forward.first(static_cast<std::size_t>(levels));
  // Split where the round-trip check starts: the two calls give the same result as one.
  const int split = std::min(levels, backward_levels_);
  if (split < levels && trackPatch(used, to, *pattern_, align_, T_forward, split) != AlignStatus::kConverged)
    return false;
  fine_start = T_forward.translation();
  if (trackPatch(used.first(static_cast<std::size_t>(split)), to, *pattern_, align_, T_forward) !=
      AlignStatus::kConverged)
    return false;
  tracked = T_forward.translation();
  return true;
}

bool KltFrontend::checkBackward(const ImagePyramid& from, const ImagePyramid& to, const Eigen::Vector2f& p,
                                const Eigen::Vector2f& tracked, const Eigen::Vector2f& flow_guess,
                                const Eigen::Vector2f& fine_start, int levels, float max_recovered_dist2,
                                CameraState& owner, int backward_slot) const {
  // The backward track starts from the negated guess, so a correct prior lands it near p again. A
  // check on fewer levels than the forward track starts where undoing the forward track's coarse
  // levels would put it: p plus what its finer levels moved.
  const int split = std::min(levels, backward_levels_);
  const Eigen::Vector2f start =
      split < levels ? Eigen::Vector2f(p + (tracked - fine_start)) : Eigen::Vector2f(tracked - flow_guess);
  SE2f T_backward(0.f, start);
  // The next frame's forward templates, on the levels the check needs; the others on demand.
  const std::span<PatchTemplate> backward = owner.slot(backward_slot).first(static_cast<std::size_t>(split));
  buildPyramidPatch(to, tracked, *pattern_, backward);
  owner.built_levels[static_cast<std::size_t>(backward_slot)] = split;
  if (trackPatch(backward, from, *pattern_, align_, T_backward) != AlignStatus::kConverged) return false;
  return (T_backward.translation() - p).squaredNorm() <= max_recovered_dist2;
}

bool KltFrontend::trackChecked(std::span<const PatchTemplate> forward, const ImagePyramid& from, const ImagePyramid& to,
                               const Eigen::Vector2f& p, const Eigen::Vector2f& flow_guess, int levels,
                               float max_recovered_dist2, CameraState& owner, int backward_slot,
                               Eigen::Vector2f& result) const {
  Eigen::Vector2f tracked, fine_start;
  if (!trackForward(forward, to, p, flow_guess, levels, tracked, fine_start)) return false;
  if (!checkBackward(from, to, p, tracked, flow_guess, fine_start, levels, max_recovered_dist2, owner, backward_slot))
    return false;
  result = tracked;
  return true;
}

const MotionField* KltFrontend::priorField(int camera, const DecodedStereoFrame& input, FrontendStats& stats) {
  if (!input.has_motion || config_.prior_mode == PriorMode::kNone) return nullptr;
  const auto c = static_cast<std::size_t>(camera);
  return cameras_[c].bridge.prior(input.motion[c], input.frames_missing_before, stats.bridged[c]);
}

bool KltFrontend::trustVector(const MotionBlock& block, const CameraState& cam, const Eigen::Vector2f& p) const {
  if (config_.prior_reject_inconsistent && block.outlier) return false;
  const int min_side = config_.prior_min_block_px;
  if (block.w * block.h < min_side * min_side) return false;
  if (config_.prior_max_qp > 0 && block.qp > config_.prior_max_qp) return false;
  if (config_.prior_max_residual_px <= 0.0) return true;
  // How well the vector predicts the point's 8x8 neighbourhood: the mean absolute difference between
  // the previous image around p and the current image around p + vector (bilinear), divided by the
  // neighbourhood's mean gradient. To first order |I(x + e) - I(x)| = |grad I . e|, so the ratio is
  // the vector's misalignment in pixels whatever the texture's contrast (noise sets a floor).
  constexpr int kHalf = 4;
  const FloatView from = cam.prev().level(0);
  const FloatView to = cam.cur().level(0);
  const float qx = p.x() + block.dx, qy = p.y() + block.dy;
  const auto inside = [](const FloatView& image, float x, float y) {
    return x - kHalf >= 0.f && y - kHalf >= 0.f && x + kHalf + 1.f < static_cast<float>(image.width) &&
           y + kHalf + 1.f < static_cast<float>(image.height);
  };
  if (!inside(from, p.x(), p.y()) || !inside(to, qx, qy)) return false;  // no neighbourhood to compare
  float residual = 0.f, gradient = 0.f;
  for (int dy = -kHalf; dy < kHalf; ++dy) {
    for (int dx = -kHalf; dx < kHalf; ++dx) {
      const float x = p.x() + static_cast<float>(dx), y = p.y() + static_cast<float>(dy);
      const float a = sampleBilinear(from, x, y);
      residual += std::abs(a - sampleBilinear(to, qx + static_cast<float>(dx), qy + static_cast<float>(dy)));
      gradient +=
          0.5f * (std::abs(sampleBilinear(from, x + 1.f, y) - a) + std::abs(sampleBilinear(from, x, y + 1.f) - a));
    }
  }
  return residual <= static_cast<float>(config_.prior_max_residual_px) * std::max(gradient, 1.f);
}

void KltFrontend::trackPart(int camera, int part, std::size_t begin, std::size_t end) {
  if (!have_previous_) return;
  CameraState& cam = cameras_[static_cast<std::size_t>(camera)];
  TemporalPart& out = cam.parts[static_cast<std::size_t>(part)];
  TemporalStats& ts = out.stats;
  const MotionField* field = cam.field;
  const ImagePyramid& from = cam.prev();
  const ImagePyramid& to = cam.cur();
  const PriorMode mode = config_.prior_mode;
  const float tolerance = static_cast<float>(config_.consensus_tolerance_px2);
  const float agree_radius2 = static_cast<float>(config_.prior_agree_radius_px * config_.prior_agree_radius_px);
  const float rescue_min2 = static_cast<float>(config_.prior_rescue_min_px * config_.prior_rescue_min_px);
  const Eigen::Vector2f zero = Eigen::Vector2f::Zero();
  const int all_levels = num_levels_;
  // A bridged field is an older frame's motion, less exact: its guesses get the whole pyramid. So do
  // of_then_mv's, whose prior only rescues points the plain track lost: the hard ones, where a vector
  // that missed by a few pixels needs the coarse levels (measured: shortened there, it loses them).
  const bool whole_pyramid = cam.field_bridged || mode == PriorMode::kOfThenMv;
  const int prior_levels = whole_pyramid ? all_levels : prior_levels_;
  // retry_previous_flow: a flow under a pixel would start the retry where the plain track started.
  // An unknown flow is searched for once the frame is known (retryFromPreviousFlow).
  const bool retry_flow = retry_flow_ && (!cam.flow_known || cam.previous_flow.squaredNorm() >= 1.f);

  for (std::size_t i = begin; i < end; ++i) {
    const Eigen::Vector2f p = cam.points[i];
    if (i + 1 < end) {
      // The next point's patches in both images, fetched while this one is tracked: the pyramids
      // are larger than the cache and each patch is touched once per frame.
      prefetchPyramidPatch(to, cam.points[i + 1], *pattern_, kPrefetchMarginPx, 2);
      prefetchPyramidPatch(from, cam.points[i + 1], *pattern_, kPrefetchMarginPx, 2);
      // And its templates, written a frame ago and long out of the nearer caches.
      const int next_slot = cam.slots[i + 1];
      prefetchTemplates(
          cam.slot(next_slot).first(static_cast<std::size_t>(cam.built_levels[static_cast<std::size_t>(next_slot)])));
    }
    const MotionBlock* block = nullptr;
    if (field != nullptr)
      block = field->blockAt(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
    ts.with_vector += block != nullptr;
    if (block != nullptr && !trustVector(*block, cam, p)) {
      block = nullptr;
      ++ts.distrusted;
    }
    const bool has_vector = block != nullptr;
    const Eigen::Vector2f mv = has_vector ? Eigen::Vector2f(block->dx, block->dy) : zero;

    // A zero vector starts the prior track where the plain one starts: the same track, run once.
    const bool same_start = has_vector && mv.x() == 0.f && mv.y() == 0.f && prior_levels == all_levels;

    // The modes differ only in which guesses run and how their results merge.
    bool run_plain = false, run_prior = false, plain_ok = false, prior_ok = false;
    Eigen::Vector2f plain_px = p, prior_px = p + mv;  // a failed track leaves its guess in the trace
    switch (mode) {
      case PriorMode::kNone:
        run_plain = true;
        break;
      case PriorMode::kMv:
        run_prior = has_vector;
        run_plain = !has_vector;  // without a vector the prior is the previous position
        break;
      case PriorMode::kOfThenMv:
      case PriorMode::kMvThenOf:
      case PriorMode::kMvParallelOf:
        run_plain = true;
        run_prior = has_vector;
        break;
    }
    const int forward_slot = cam.slots[i];
    const int plain_slot = out.acquire(), prior_slot = out.acquire();
    const auto forward = [&](int levels) { return cam.trackedTemplates(forward_slot, from, p, levels, *pattern_); };
    const auto attempt = [&](const Eigen::Vector2f& guess, int levels, int backward_slot, Eigen::Vector2f& tracked) {
      return trackChecked(forward(levels), from, to, p, guess, levels, temporal_round_trip2_, cam, backward_slot,
                          tracked);
    };
    if (mode == PriorMode::kMvParallelOf && run_prior) {
      // The plain track first, with its round trip. When the prior's forward track agrees with a
      // plain track that passed, the point is kept from the plain track whatever the prior's round
      // trip says, so that one is skipped; the outcome equals running both checks.
      Eigen::Vector2f plain_fine_start, prior_fine_start;
      const bool plain_forward = trackForward(forward(all_levels), to, p, zero, all_levels, plain_px, plain_fine_start);
      plain_ok = plain_forward && checkBackward(from, to, p, plain_px, zero, plain_fine_start, all_levels,
                                                temporal_round_trip2_, cam, plain_slot);
      const bool confirmed = plain_ok && agree_radius2 > 0.f && (p + mv - plain_px).squaredNorm() <= agree_radius2;
      ts.prior_confirmed += confirmed && !same_start;
      if (same_start || confirmed) {
        prior_px = plain_px;
        prior_ok = plain_ok;
      } else if (!plain_ok && mv.squaredNorm() < rescue_min2) {
        prior_ok = false;  // it could only rescue the point: too short a vector for that (prior_rescue_min_px)
      } else {
        const bool prior_forward =
            trackForward(forward(prior_levels), to, p, mv, prior_levels, prior_px, prior_fine_start);
        const bool agree = plain_ok && prior_forward && (plain_px - prior_px).squaredNorm() <= tolerance;
        prior_ok = agree || (prior_forward && checkBackward(from, to, p, prior_px, mv, prior_fine_start, prior_levels,
                                                            temporal_round_trip2_, cam, prior_slot));
      }
    } else {
      // The retry of the sequential modes runs only from a different start: from the same one it
      // would fail again.
      if (mode == PriorMode::kMvThenOf && run_prior) {
        prior_ok = attempt(mv, prior_levels, prior_slot, prior_px);
        run_plain = !prior_ok && !same_start;
      }
      if (run_plain) plain_ok = attempt(zero, all_levels, plain_slot, plain_px);
      if (mode == PriorMode::kOfThenMv) run_prior = run_prior && !plain_ok && !same_start;
      if (run_prior && mode != PriorMode::kMvThenOf) prior_ok = attempt(mv, prior_levels, prior_slot, prior_px);
    }
    ts.tracked_plain += plain_ok;
    ts.tracked_prior += prior_ok;

    bool keep = false;
    bool keep_prior = false;
    Eigen::Vector2f result = zero;
    if (plain_ok && prior_ok) {
      // Only kMvParallelOf gets here: two answers that disagree mean one of them is a false match.
      if ((plain_px - prior_px).squaredNorm() <= tolerance) {
        keep = true;
        result = plain_px;
      } else {
        ++ts.consensus_rejections;
      }
    } else if (plain_ok) {
      keep = true;
      result = plain_px;
    } else if (prior_ok) {
      keep = true;
      keep_prior = true;
      result = prior_px;
      ts.rescued += run_plain;  // the plain track was tried and failed
    }
    // The kept result's backward templates become the point's templates; everything else is freed
    // (the forward slot once the point's retry is settled).
    out.release(keep && keep_prior ? plain_slot : prior_slot);
    if (!keep) out.release(plain_slot);

    PointTrace trace;
    trace.track_id = cam.ids[i];
    trace.previous_px = p;
    trace.prior_px = p + mv;
    trace.has_prior = has_vector;
    trace.tracked_px = keep ? result : (prior_ok ? prior_px : plain_px);
    trace.kept = keep;
    out.traces.push_back(trace);
    if (!keep) {
      // The last resort of every mode (retry_previous_flow), decided once the whole frame is known:
      // the point keeps its templates until then. From the same start it would fail again.
      // It holds its place in the next frame's list, which keeps the ids in ascending order.
      if (retry_flow && (!has_vector || !cam.flow_known || (mv - cam.previous_flow).squaredNorm() >= 1.f)) {
        out.retry_candidates.push_back({out.ids.size(), out.traces.size() - 1, forward_slot});
        out.ids.push_back(cam.ids[i]);
        out.points.push_back(p);
        out.slots.push_back(-1);
        continue;
      }
      out.release(forward_slot);
      ++ts.lost;
      continue;
    }
    out.release(forward_slot);
    out.ids.push_back(cam.ids[i]);
    out.points.push_back(result);
    out.slots.push_back(keep_prior ? prior_slot : plain_slot);
    countKept(out, result, trace);
  }
}

void KltFrontend::endCamera(int camera, FrontendStats& stats) {
  if (!have_previous_) return;
  CameraState& cam = cameras_[static_cast<std::size_t>(camera)];
  TemporalPart& step = cam.step;
  for (TemporalPart& part : cam.parts) {
    step.append(part);
    cam.free_slots.insert(cam.free_slots.end(), part.free_slots.begin(), part.free_slots.end());
    part.free_slots.clear();
  }
  step.stats.previous = static_cast<int>(cam.points.size());
  const bool retry_lost_some = retryFromPreviousFlow(cam);
  stats.temporal[static_cast<std::size_t>(camera)] = step.stats;
  std::swap(cam.ids, step.ids);
  std::swap(cam.points, step.points);
  std::swap(cam.slots, step.slots);
  // The candidates the retry lost leave their places (slot -1, no templates); the others keep
  // theirs, so the ids still ascend.
  if (retry_lost_some) cam.retain([&](std::size_t i, std::size_t) { return cam.slots[i] >= 0; });
  // The image flow the next frame's retries start from. With no track kept it stays what it was:
  // the camera's last known motion beats none.
  if (!step.flow_x.empty()) {
    const auto median = [](std::vector<float>& v) {
      const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
      std::nth_element(v.begin(), mid, v.end());
      return *mid;
    };
    cam.previous_flow = Eigen::Vector2f(median(step.flow_x), median(step.flow_y));
    cam.flow_known = true;
  }
}

void KltFrontend::countKept(TemporalPart& out, const Eigen::Vector2f& tracked, const PointTrace& trace) const {
  const Eigen::Vector2f p = trace.previous_px;
  ++out.stats.kept;
  if (retry_flow_) {
    out.flow_x.push_back(tracked.x() - p.x());
    out.flow_y.push_back(tracked.y() - p.y());
  }
  if (trace.has_prior) {
    out.guess_dist_plain_px.push_back((tracked - p).norm());
    out.guess_dist_prior_px.push_back((tracked - trace.prior_px).norm());
  }
}

bool KltFrontend::retryFromPreviousFlow(CameraState& cam) {
  TemporalPart& step = cam.step;
  TemporalStats& ts = step.stats;
  if (step.retry_candidates.empty()) return false;
  // An ordinary frame loses a few points (they left the view, were occluded or changed); a turn
  // beyond the pyramid's reach loses most at once, and there the retry is the only way to keep the
  // frame's tracks. Retrying the few as well raised raw MH_03's ATE (retry_min_lost_fraction,
  // configs/README.md).
  const int lost_by_guesses = ts.previous - ts.kept;
  bool retry = static_cast<double>(lost_by_guesses) >= config_.retry_min_lost_fraction * ts.previous;
  const ImagePyramid& from = cam.prev();
  const ImagePyramid& to = cam.cur();
  if (retry && !cam.flow_known) {
    // No step has measured this camera's flow yet (the run, or tracking after reset(), started in
    // fast motion): the whole image's shift stands in for it. The round trip still checks each track.
    const int coarsest = num_levels_ - 1;
    const std::optional<Eigen::Vector2f> shift =
        cam.shift_search.estimate(from.level(coarsest), to.level(coarsest), static_cast<float>(1 << coarsest));
    retry = shift && shift->squaredNorm() >= 1.f;
    if (retry) cam.previous_flow = *shift;
    ts.flow_searched = retry ? 1 : 0;
  }
  bool any_lost = false;
  for (const RetryCandidate& candidate : step.retry_candidates) {
    PointTrace& trace = step.traces[candidate.trace];
    const int slot = retry ? cam.acquire() : -1;
    Eigen::Vector2f tracked = trace.previous_px + cam.previous_flow;
    const bool ok =
        retry &&
        trackChecked(cam.trackedTemplates(candidate.slot, from, trace.previous_px, num_levels_, *pattern_), from, to,
                     trace.previous_px, cam.previous_flow, num_levels_, temporal_round_trip2_, cam, slot, tracked);
    cam.release(candidate.slot);
    if (!ok) {
      if (slot >= 0) cam.release(slot);
      step.slots[candidate.next] = -1;
      any_lost = true;
      ++ts.lost;
      continue;
    }
    trace.tracked_px = tracked;
    trace.kept = true;
    ++ts.flow_retried;
    step.points[candidate.next] = tracked;
    step.slots[candidate.next] = slot;
    countKept(step, tracked, trace);
  }
  return any_lost;
}

void KltFrontend::thinTracks(FrontendStats& stats) {
  CameraState& left = cameras_[0];
  CameraState& right = cameras_[1];
  const float min_distance2 = static_cast<float>(config_.thin_when_full_px * config_.thin_when_full_px);
  // Cells are half the distance wide: two points closer than it lie at most two cells apart.
  constexpr int kReach = 2;
  const auto cellOf = [&](float v, int cells) {
    return std::clamp(static_cast<int>(std::floor(v / thin_cell_px_)), 0, cells - 1);
  };
  thinned_ids_.clear();
  // Ids are issued in increasing order: the list is oldest first, so the older of two close tracks
  // is always the one already kept.
  left.retain([&](std::size_t i, std::size_t kept) {
    const Eigen::Vector2f p = left.points[i];
    const int cx = cellOf(p.x(), thin_cols_), cy = cellOf(p.y(), thin_rows_);
    for (int y = std::max(0, cy - kReach); y <= std::min(thin_rows_ - 1, cy + kReach); ++y) {
      for (int x = std::max(0, cx - kReach); x <= std::min(thin_cols_ - 1, cx + kReach); ++x) {
        const int other = thin_grid_[static_cast<std::size_t>(y * thin_cols_ + x)];
        if (other >= 0 && (left.points[static_cast<std::size_t>(other)] - p).squaredNorm() < min_distance2) {
          thinned_ids_.push_back(left.ids[i]);
          return false;
        }
      }
    }
    thin_grid_[static_cast<std::size_t>(cy * thin_cols_ + cx)] = static_cast<int>(kept);
    return true;
  });
  // The grid is cleared through the kept points: far fewer than its cells.
  for (const Eigen::Vector2f& p : left.points) {
    thin_grid_[static_cast<std::size_t>(cellOf(p.y(), thin_rows_) * thin_cols_ + cellOf(p.x(), thin_cols_))] = -1;
  }
  stats.thinned = static_cast<int>(thinned_ids_.size());
  if (thinned_ids_.empty()) return;
  // The same tracks in the right camera: both id lists ascend, one merge pass.
  std::size_t d = 0;
  right.retain([&](std::size_t r, std::size_t) {
    while (d < thinned_ids_.size() && thinned_ids_[d] < right.ids[r]) ++d;
    return d == thinned_ids_.size() || thinned_ids_[d] != right.ids[r];
  });
}

Eigen::Vector2f KltFrontend::stereoGuess(const Eigen::Vector2f& p) const {
  const double depth =
      config_.matching_guess == StereoGuess::kAverageDepth ? average_depth_m_ : config_.matching_default_depth_m;
  Eigen::Vector3d bearing;
  Eigen::Vector2d uv;
  if (cameras_model_[0].unproject(p.cast<double>(), bearing) &&
      cameras_model_[1].project(T_cam1_cam0_ * (bearing * depth), uv)) {
    return uv.cast<float>();
  }
  return p;
}

void KltFrontend::detectAndMatch(const DecodedStereoFrame& input, FrontendStats& stats) {
  CameraState& left = cameras_[0];
  CameraState& right = cameras_[1];
  new_points_.clear();
  const int room = max_points_ - static_cast<int>(left.points.size());
  if (room <= 0) return;
  stats.detected = detector_.detect(input.images[0].view(), left.points, detector_params_, room, new_points_);
  const int right_room = max_points_ - static_cast<int>(right.points.size());
  for (const Eigen::Vector2f& p : new_points_) {
    const std::uint64_t id = next_track_id_++;
    const int left_slot = left.addDetected(id, p, *pattern_);
    if (stats.stereo_matched >= right_room) continue;
    const Eigen::Vector2f guess = stereoGuess(p);
    Eigen::Vector2f matched;
    const int right_slot = right.acquire();
    if (trackChecked(left.slot(left_slot), left.cur(), right.cur(), p, guess - p, num_levels_, stereo_round_trip2_,
                     right, right_slot, matched)) {
      right.ids.push_back(id);
      right.points.push_back(matched);
      right.slots.push_back(right_slot);
      ++stats.stereo_matched;
    } else {
      right.release(right_slot);
    }
  }
}

void KltFrontend::rematchStereo(FrontendStats& stats) {
  CameraState& left = cameras_[0];
  CameraState& right = cameras_[1];
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
    const int right_slot = right.acquire();
    // The left slot holds the point's templates in the current image (its backward track built them).
    if (trackChecked(left.trackedTemplates(left.slots[l], left.cur(), p, num_levels_, *pattern_), left.cur(),
                     right.cur(), p, guess - p, num_levels_, stereo_round_trip2_, right, right_slot, matched)) {
      rematch_ids_.push_back(id);
      rematch_points_.push_back(matched);
      rematch_slots_.push_back(right_slot);
      --room;
    } else {
      right.release(right_slot);
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

void KltFrontend::detectRightOnly(const DecodedStereoFrame& input, FrontendStats& stats) {
  CameraState& right = cameras_[1];
  new_points_.clear();
  const int room = max_points_ - static_cast<int>(right.points.size());
  if (room <= 0) return;
  stats.detected_right_only =
      detector_.detect(input.images[1].view(), right.points, right_detector_params_, room, new_points_, right_overlap_);
  // Ids are issued in increasing order, so the right list stays sorted for filterEpipolar's merge.
  for (const Eigen::Vector2f& p : new_points_) {
    right.addDetected(next_track_id_++, p, *pattern_);
  }
}

void KltFrontend::filterEpipolar(FrontendStats& stats) {
  CameraState& left = cameras_[0];
  CameraState& right = cameras_[1];
  // Both id lists are ascending (ids are issued in increasing order and removals keep the order),
  // so one merge pass pairs them.
  std::size_t l = 0;
  const float threshold = static_cast<float>(config_.epipolar_error);
  right.retain([&](std::size_t r, std::size_t) {
    const std::uint64_t id = right.ids[r];
    while (l < left.ids.size() && left.ids[l] < id) ++l;
    if (l == left.ids.size() || left.ids[l] != id) return true;  // a right-only track
    Eigen::Vector3d f0, f1;
    const bool ok0 = cameras_model_[0].unproject(left.points[l].cast<double>(), f0);
    const bool ok1 = cameras_model_[1].unproject(right.points[r].cast<double>(), f1);
    const bool keep = ok0 && ok1 && std::abs(f0.dot(essential_ * f1)) <= threshold;
    if (!keep) ++stats.epipolar_rejected;
    return keep;
  });
}

void KltFrontend::track(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats) {
  beginFrame(input, stats);
  trackCamera(0, input, stats);
  trackCamera(1, input, stats);
  endFrame(input, out, stats);
}

void KltFrontend::beginFrame(const DecodedStereoFrame& input, FrontendStats& stats) {
  frame_start_ = std::chrono::steady_clock::now();
  for (int c = 0; c < 2; ++c) {
    const GrayImage& image = input.images[static_cast<std::size_t>(c)];
    if (image.width() != width_ || image.height() != height_) {
      throw InputError(fmt::format("frontend: camera {} image is {}x{}, the calibration says {}x{}", c, image.width(),
                                   image.height(), width_, height_));
    }
  }
  stats.reserve(static_cast<std::size_t>(max_points_));
  stats.clear();
  stats.frame_index = input.frame_index;
  if (std::isfinite(input.depth_hint_m) && input.depth_hint_m > 0.0) average_depth_m_ = input.depth_hint_m;
  presmooth_ = appliesTo(config_.presmooth, input.decoded);
  retry_flow_ = appliesTo(config_.retry_previous_flow, input.decoded);
}

void KltFrontend::trackCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats) {
  beginCamera(camera, input, stats);
  trackPart(camera, 0, 0, trackedPoints(camera));
  endCamera(camera, stats);
}

void KltFrontend::beginCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats) {
  CameraState& cam = cameras_[static_cast<std::size_t>(camera)];
  cam.current = 1 - cam.current;
  cam.pyramids[static_cast<std::size_t>(cam.current)].build(input.images[static_cast<std::size_t>(camera)].view(),
                                                            presmooth_);
  cam.step.clear();
  cam.field = priorField(camera, input, stats);  // without a previous frame: remembers a P-frame field for bridging
  cam.field_bridged = stats.bridged[static_cast<std::size_t>(camera)];
  if (!have_previous_) return;
  // Each share takes its scratch slots now, before the shares may run on two threads.
  for (TemporalPart& part : cam.parts) {
    part.clear();
    for (int k = 0; k < kScratchSlots; ++k) part.release(cam.acquire());
  }
}

void KltFrontend::endFrame(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats) {
  for (const CameraState& cam : cameras_) {
    stats.guess_dist_plain_px.insert(stats.guess_dist_plain_px.end(), cam.step.guess_dist_plain_px.begin(),
                                     cam.step.guess_dist_plain_px.end());
    stats.guess_dist_prior_px.insert(stats.guess_dist_prior_px.end(), cam.step.guess_dist_prior_px.begin(),
                                     cam.step.guess_dist_prior_px.end());
  }
  // Every track survived and the capacity is full: no point could be detected. Crowded tracks give
  // way (thin_when_full_px).
  if (have_previous_ && config_.thin_when_full_px > 0.0 && static_cast<int>(cameras_[0].points.size()) >= max_points_)
    thinTracks(stats);
  if (have_previous_ && config_.stereo_rematch) rematchStereo(stats);
  detectAndMatch(input, stats);
  if (config_.detection_nonoverlap) detectRightOnly(input, stats);
  filterEpipolar(stats);
  have_previous_ = true;

  out.reserve(static_cast<std::size_t>(max_points_));
  out.clear();
  out.t_ns = input.t_ns;
  out.frame_index = input.frame_index;
  out.frames_missing_before = input.frames_missing_before;
  for (int c = 0; c < 2; ++c) {
    const CameraState& cam = cameras_[static_cast<std::size_t>(c)];
    auto& observations = out.observations[static_cast<std::size_t>(c)];
    for (std::size_t i = 0; i < cam.ids.size(); ++i) observations.push_back({cam.ids[i], cam.points[i]});
  }
  stats.num_left = static_cast<int>(out.observations[0].size());
  stats.num_right = static_cast<int>(out.observations[1].size());
  stats.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_start_).count();
}

}  // namespace voca
