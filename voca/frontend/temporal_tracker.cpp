#include "voca/frontend/temporal_tracker.h"

#include <algorithm>
#include <cmath>

namespace voca {

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

}  // namespace

void TemporalShare::reserve(std::size_t max_points, std::size_t scratch_slots) {
  ids.reserve(max_points);
  points.reserve(max_points);
  slots.reserve(max_points);
  traces.reserve(max_points);
  retry_candidates.reserve(max_points);
  for (auto* v : {&flow_x, &flow_y, &guess_dist_plain_px, &guess_dist_prior_px}) v->reserve(max_points);
  free_slots.reserve(max_points + scratch_slots);
}

void TemporalShare::clear() {
  stats = {};
  ids.clear();
  points.clear();
  slots.clear();
  traces.clear();
  retry_candidates.clear();
  for (auto* v : {&flow_x, &flow_y, &guess_dist_plain_px, &guess_dist_prior_px}) v->clear();
}

void TemporalShare::append(const TemporalShare& other) {
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

TemporalTracker::TemporalTracker(const FrontendConfig& config, const RoundTripTracker& klt, int max_points,
                                 int max_width, int max_height, const CameraTracks& camera)
    : config_(config),
      klt_(klt),
      num_levels_(config.pyramid_levels + 1),
      prior_levels_(config.prior_pyramid_levels < 0 ? num_levels_ : config.prior_pyramid_levels + 1),
      round_trip2_(static_cast<float>(config.max_recovered_dist2_px2)),
      bridge_(max_width, max_height, config.bridge_iframes, config.prior_reject_inconsistent) {
  for (TemporalShare& share : shares_) share.reserve(static_cast<std::size_t>(max_points), kScratchSlotsPerShare);
  step_.reserve(static_cast<std::size_t>(max_points), kScratchSlotsPerShare);
  // The pyramids are sized for the largest image: their coarsest level is the largest the search sees.
  const FloatView coarsest = camera.pyramids[0].level(num_levels_ - 1);
  shift_search_ = ImageShiftSearch(coarsest.width, coarsest.height);
}

void TemporalTracker::reset() {
  for (TemporalShare& share : shares_) share.free_slots.clear();  // a step cut short may have left scratch slots
  step_.clear();
  bridge_.clear();
  previous_flow_.setZero();
  flow_known_ = false;
}

void TemporalTracker::begin(const MotionField* motion, int frames_missing_before, bool following,
                            bool retry_previous_flow, CameraTracks& camera) {
  step_.clear();
  field_bridged_ = false;
  // Also without a previous frame: the bridge remembers a P-frame's field for a later I-frame.
  field_ = motion != nullptr && config_.prior_mode != PriorMode::kNone
               ? bridge_.prior(*motion, frames_missing_before, field_bridged_)
               : nullptr;
  following_ = following;
  retry_flow_ = retry_previous_flow;
  if (!following_) return;
  // Each share takes its scratch slots now, before the shares may run on threads of their own.
  for (TemporalShare& share : shares_) {
    share.clear();
    share.free_slots.takeFrom(camera.free_slots, kScratchSlotsPerShare);
  }
}

bool TemporalTracker::trustVector(const MotionBlock& block, const CameraTracks& camera,
                                  const Eigen::Vector2f& p) const {
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
  const FloatView from = camera.prev().level(0);
  const FloatView to = camera.cur().level(0);
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

void TemporalTracker::trackShare(int share, std::size_t begin, std::size_t end, CameraTracks& camera) {
  if (!following_) return;
  TemporalShare& out = shares_[static_cast<std::size_t>(share)];
  TemporalStats& ts = out.stats;
  const MotionField* field = field_;
  const PatchPattern& pattern = klt_.pattern();
  const ImagePyramid& from = camera.prev();
  const ImagePyramid& to = camera.cur();
  const PriorMode mode = config_.prior_mode;
  const float tolerance = static_cast<float>(config_.consensus_tolerance_px2);
  const float agree_radius2 = static_cast<float>(config_.prior_agree_radius_px * config_.prior_agree_radius_px);
  const float rescue_min2 = static_cast<float>(config_.prior_rescue_min_px * config_.prior_rescue_min_px);
  const Eigen::Vector2f zero = Eigen::Vector2f::Zero();
  const int all_levels = num_levels_;
  // A bridged field is an older frame's motion, less exact: its guesses get the whole pyramid. So do
  // of_then_mv's, whose prior only rescues points the plain track lost: the hard ones, where a vector
  // that missed by a few pixels needs the coarse levels (measured: shortened there, it loses them).
  const bool whole_pyramid = field_bridged_ || mode == PriorMode::kOfThenMv;
  const int prior_levels = whole_pyramid ? all_levels : prior_levels_;
  // retry_previous_flow: a flow under a pixel would start the retry where the plain track started.
  // An unknown flow is searched for once the frame is known (retryFromPreviousFlow).
  const bool retry_flow = retry_flow_ && (!flow_known_ || previous_flow_.squaredNorm() >= 1.f);

  for (std::size_t i = begin; i < end; ++i) {
    const Eigen::Vector2f p = camera.points[i];
    if (i + 1 < end) {
      // The next point's patches in both images, fetched while this one is tracked: the pyramids
      // are larger than the cache and each patch is touched once per frame.
      prefetchPyramidPatch(to, camera.points[i + 1], pattern, kPrefetchMarginPx, 2);
      prefetchPyramidPatch(from, camera.points[i + 1], pattern, kPrefetchMarginPx, 2);
      // And its templates, written a frame ago and long out of the nearer caches.
      prefetchTemplates(camera.templates.built(camera.slots[i + 1]));
    }
    const MotionBlock* block = nullptr;
    if (field != nullptr)
      block = field->blockAt(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
    ts.with_vector += block != nullptr;
    if (block != nullptr && !trustVector(*block, camera, p)) {
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
    const int forward_slot = camera.slots[i];
    const int plain_slot = out.free_slots.acquire(), prior_slot = out.free_slots.acquire();
    const auto forward = [&](int levels) {
      return camera.templates.ensureBuilt(forward_slot, from, p, levels, pattern);
    };
    const auto attempt = [&](const Eigen::Vector2f& guess, int levels, int backward_slot, Eigen::Vector2f& tracked) {
      return klt_.track(forward(levels), from, to, p, guess, levels, round_trip2_, camera.templates, backward_slot,
                        tracked);
    };
    if (mode == PriorMode::kMvParallelOf && run_prior) {
      // The plain track first, with its round trip. When the prior's forward track agrees with a
      // plain track that passed, the point is kept from the plain track whatever the prior's round
      // trip says, so that one is skipped; the outcome equals running both checks.
      Eigen::Vector2f plain_fine_start, prior_fine_start;
      const bool plain_forward =
          klt_.trackForward(forward(all_levels), to, p, zero, all_levels, plain_px, plain_fine_start);
      plain_ok = plain_forward && klt_.checkBackward(from, to, p, plain_px, zero, plain_fine_start, all_levels,
                                                     round_trip2_, camera.templates, plain_slot);
      const bool confirmed = plain_ok && agree_radius2 > 0.f && (p + mv - plain_px).squaredNorm() <= agree_radius2;
      ts.prior_confirmed += confirmed && !same_start;
      if (same_start || confirmed) {
        prior_px = plain_px;
        prior_ok = plain_ok;
      } else if (!plain_ok && mv.squaredNorm() < rescue_min2) {
        prior_ok = false;  // it could only rescue the point: too short a vector for that (prior_rescue_min_px)
      } else {
        const bool prior_forward =
            klt_.trackForward(forward(prior_levels), to, p, mv, prior_levels, prior_px, prior_fine_start);
        const bool agree = plain_ok && prior_forward && (plain_px - prior_px).squaredNorm() <= tolerance;
        prior_ok =
            agree || (prior_forward && klt_.checkBackward(from, to, p, prior_px, mv, prior_fine_start, prior_levels,
                                                          round_trip2_, camera.templates, prior_slot));
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
    out.free_slots.release(keep && keep_prior ? plain_slot : prior_slot);
    if (!keep) out.free_slots.release(plain_slot);

    PointTrace trace;
    trace.track_id = camera.ids[i];
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
      if (retry_flow && (!has_vector || !flow_known_ || (mv - previous_flow_).squaredNorm() >= 1.f)) {
        out.retry_candidates.push_back({out.ids.size(), out.traces.size() - 1, forward_slot});
        out.ids.push_back(camera.ids[i]);
        out.points.push_back(p);
        out.slots.push_back(-1);
        continue;
      }
      out.free_slots.release(forward_slot);
      ++ts.lost;
      continue;
    }
    out.free_slots.release(forward_slot);
    out.ids.push_back(camera.ids[i]);
    out.points.push_back(result);
    out.slots.push_back(keep_prior ? prior_slot : plain_slot);
    countKept(out, result, trace);
  }
}

void TemporalTracker::finish(CameraTracks& camera) {
  if (!following_) return;
  for (TemporalShare& share : shares_) {
    step_.append(share);
    share.free_slots.giveAllTo(camera.free_slots);
  }
  step_.stats.previous = static_cast<int>(camera.points.size());
  const bool retry_lost_some = retryFromPreviousFlow(camera);
  std::swap(camera.ids, step_.ids);
  std::swap(camera.points, step_.points);
  std::swap(camera.slots, step_.slots);
  // The candidates the retry lost leave their places (slot -1, no templates); the others keep
  // theirs, so the ids still ascend.
  if (retry_lost_some) camera.retain([&](std::size_t i, std::size_t) { return camera.slots[i] >= 0; });
  // The image flow the next frame's retries start from. With no track kept it stays what it was:
  // the camera's last known motion beats none.
  if (!step_.flow_x.empty()) {
    const auto median = [](std::vector<float>& v) {
      const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
      std::nth_element(v.begin(), mid, v.end());
      return *mid;
    };
    previous_flow_ = Eigen::Vector2f(median(step_.flow_x), median(step_.flow_y));
    flow_known_ = true;
  }
}

void TemporalTracker::countKept(TemporalShare& out, const Eigen::Vector2f& tracked, const PointTrace& trace) const {
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

bool TemporalTracker::retryFromPreviousFlow(CameraTracks& camera) {
  TemporalShare& step = step_;
  TemporalStats& ts = step.stats;
  if (step.retry_candidates.empty()) return false;
  // An ordinary frame loses a few points (they left the view, were occluded or changed); a turn
  // beyond the pyramid's reach loses most at once, and there the retry is the only way to keep the
  // frame's tracks. Retrying the few as well raised raw MH_03's ATE (retry_min_lost_fraction,
  // configs/README.md).
  const int lost_by_guesses = ts.previous - ts.kept;
  bool retry = static_cast<double>(lost_by_guesses) >= config_.retry_min_lost_fraction * ts.previous;
  const ImagePyramid& from = camera.prev();
  const ImagePyramid& to = camera.cur();
  if (retry && !flow_known_) {
    // No step has measured this camera's flow yet (the run, or tracking after reset(), started in
    // fast motion): the whole image's shift stands in for it. The round trip still checks each track.
    const int coarsest = num_levels_ - 1;
    const std::optional<Eigen::Vector2f> shift =
        shift_search_.estimate(from.level(coarsest), to.level(coarsest), static_cast<float>(1 << coarsest));
    retry = shift && shift->squaredNorm() >= 1.f;
    if (retry) previous_flow_ = *shift;
    ts.flow_searched = retry ? 1 : 0;
  }
  bool any_lost = false;
  for (const TemporalShare::RetryCandidate& candidate : step.retry_candidates) {
    PointTrace& trace = step.traces[candidate.trace];
    const int slot = retry ? camera.free_slots.acquire() : -1;
    Eigen::Vector2f tracked = trace.previous_px + previous_flow_;
    const bool ok = retry && klt_.track(camera.templates.ensureBuilt(candidate.slot, from, trace.previous_px,
                                                                     num_levels_, klt_.pattern()),
                                        from, to, trace.previous_px, previous_flow_, num_levels_, round_trip2_,
                                        camera.templates, slot, tracked);
    camera.free_slots.release(candidate.slot);
    if (!ok) {
      if (slot >= 0) camera.free_slots.release(slot);
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

}  // namespace voca
