#pragma once
// The KLT frontend: temporal and stereo patch tracking with codec motion-vector priors, corner
// detection and persistent track ids, with all memory fixed at construction.

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "voca/calib/calibration.h"
#include "voca/core/image.h"
#include "voca/core/stereo_frame.h"
#include "voca/core/tracked_frame.h"
#include "voca/frontend/detector.h"
#include "voca/frontend/frontend_config.h"
#include "voca/frontend/image_shift.h"
#include "voca/frontend/patch.h"
#include "voca/frontend/pyramid.h"
#include "voca/motion/motion_field.h"

namespace voca {

// Upper bounds the frontend allocates for once.
struct FrontendCapacities {
  // The largest max_points: twice what a detection grid of 16 px cells fills on a 4K image (one corner
  // per cell, ~32,000); the bound keeps a mistyped capacity from allocating gigabytes (about 8 KB per
  // point in all).
  static constexpr int kMaxPointsBound = 1 << 16;
  int max_points = 500;  // per camera (template memory: about 6 KB per point and camera)
  int max_width = 0;     // 0 = the calibration's image size
  int max_height = 0;
};

// Temporal tracking of one camera in one frame.
struct TemporalStats {
  int previous = 0;       // points of the previous frame
  int with_vector = 0;    // of these, how many had a motion vector (possibly bridged)
  int tracked_plain = 0;  // successful tracks started from the previous position
  int tracked_prior = 0;  // successful tracks started from the MV prior
  int kept = 0;
  int lost = 0;
  int rescued = 0;       // kept from the prior after the plain track was tried and failed
  int flow_retried = 0;  // kept from the previous frame's image flow after every other guess failed
  // 1 when that retry started from the whole image's searched shift instead: no step had measured
  // the camera's flow yet (ImageShiftSearch).
  int flow_searched = 0;
  int consensus_rejections = 0;
  int distrusted = 0;       // vectors the codec-confidence checks rejected (counted in with_vector too)
  int prior_confirmed = 0;  // prior tracks not run: the vector landed near the plain track's result
  bool operator==(const TemporalStats&) const = default;
  // Adds every counter (the counts of two shares of one camera's points).
  TemporalStats& operator+=(const TemporalStats& other);
};

// What one call of KltFrontend::track did.
struct FrontendStats {
  std::int64_t frame_index = 0;
  std::array<TemporalStats, 2> temporal{};
  std::array<bool, 2> bridged{false, false};  // the camera's prior came from an earlier P-frame
  int detected = 0;                           // new left points
  int detected_right_only = 0;                // new right points where the left camera does not see
  int stereo_matched = 0;                     // of the new points, found in the right image
  int stereo_rematched = 0;                   // left tracks without a right view found there again (stereo_rematch)
  int epipolar_rejected = 0;                  // right observations dropped by the epipolar check
  int thinned = 0;                            // left tracks dropped next to an older one (thin_when_full_px)
  int num_left = 0, num_right = 0;            // observations output
  // For every kept temporal track that had a motion vector, the distance from each initial guess
  // (previous position: plain; previous position + vector: prior) to the converged position, in
  // pixels, both cameras (the paper's Fig. 5). Paired by index.
  std::vector<float> guess_dist_plain_px, guess_dist_prior_px;
  double time_ms = 0.0;

  void reserve(std::size_t max_points);
  void clear();
};

// Per-point record of the last temporal step, for overlays (the paper's Fig. 1).
struct PointTrace {
  std::uint64_t track_id = 0;
  Eigen::Vector2f previous_px = Eigen::Vector2f::Zero();
  Eigen::Vector2f prior_px = Eigen::Vector2f::Zero();  // previous + motion vector, when has_prior
  Eigen::Vector2f tracked_px = Eigen::Vector2f::Zero();
  bool has_prior = false;
  bool kept = false;
};

// Stereo KLT tracker. Not thread-safe; one instance per stream. No heap allocation in track()
// after the first frame.
class KltFrontend {
 public:
  // The rig's first two cameras are left (cam0) and right (cam1). Throws InputError for an invalid
  // config or a rig with fewer than two cameras.
  KltFrontend(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities = {});

  // Tracks the previous frame's points into this frame, detects new left points in empty cells and
  // matches them into the right image. Images must have the calibration's size (at most the capacity).
  // In StereoGuess::kAverageDepth mode the stereo guess uses the frame's depth_hint_m (the last
  // positive hint seen; the default depth until then). out carries the frame's t_ns, frame_index and
  // frames_missing_before.
  void track(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats);
  // track() in three steps, for a caller that tracks the two cameras on two threads: beginFrame,
  // then trackCamera(0) and trackCamera(1), which touch disjoint state and may run concurrently
  // (each builds its camera's pyramid and tracks its points into it), then endFrame (thinning,
  // detection, stereo matching, the epipolar check, the output). The same results as track(), bit
  // for bit, in either order of the two cameras.
  void beginFrame(const DecodedStereoFrame& input, FrontendStats& stats);
  void trackCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats);
  void endFrame(const DecodedStereoFrame& input, TrackedStereoFrame& out, FrontendStats& stats);
  // trackCamera() in three steps, to share one camera's points between two threads: beginCamera
  // (its pyramid and prior field), then trackPart(camera, 0, 0, k) and trackPart(camera, 1, k, n)
  // for any split k of its n = trackedPoints(camera) points, which may run concurrently with each
  // other and with the other camera's steps, then endCamera (the shares joined in the points' order,
  // the frame-level retry). The same results as trackCamera(), bit for bit, for every k.
  void beginCamera(int camera, const DecodedStereoFrame& input, FrontendStats& stats);
  std::size_t trackedPoints(int camera) const { return cameras_[static_cast<std::size_t>(camera)].points.size(); }
  void trackPart(int camera, int part, std::size_t begin, std::size_t end);
  void endCamera(int camera, FrontendStats& stats);
  // Forgets every track (the next frame starts from detection).
  void reset();

  // Temporal step of the last frame per camera, for visualisation.
  std::span<const PointTrace> traces(int camera) const {
    return cameras_[static_cast<std::size_t>(camera)].step.traces;
  }
  const FrontendConfig& config() const { return config_; }

 private:
  // A point every guess lost, held for the frame-level retry decision.
  struct RetryCandidate {
    std::size_t next = 0;   // its place in the next frame's lists
    std::size_t trace = 0;  // index into the camera's traces
    int slot = 0;           // the point's templates
  };
  // What the temporal step made of a run of one camera's points, in their order: the next frame's
  // points (ids, positions, template slots; a retry candidate holds slot -1 until decided), the
  // traces, the retry candidates, the kept tracks' flow and guess distances, the counters. Each of
  // the two shares a step may be split into has one, with free slots of its own: a point takes two
  // fresh slots and gives back at least as many, so two suffice. The joined step has one more.
  struct TemporalPart {
    TemporalStats stats;
    std::vector<std::uint64_t> ids;
    std::vector<Eigen::Vector2f> points;
    std::vector<int> slots;
    std::vector<PointTrace> traces;
    std::vector<RetryCandidate> retry_candidates;
    std::vector<float> flow_x, flow_y;
    std::vector<float> guess_dist_plain_px, guess_dist_prior_px;
    std::vector<int> free_slots;
    int acquire() {
      const int index = free_slots.back();
      free_slots.pop_back();
      return index;
    }
    void release(int index) { free_slots.push_back(index); }
    void reserve(std::size_t max_points);
    void clear();
    // Appends another share's results after this one's (its indices shifted to match).
    void append(const TemporalPart& other);
  };
  // Scratch slots per share: a point's plain and prior backward tracks.
  static constexpr int kScratchSlots = 2;

  struct CameraState {
    std::array<ImagePyramid, 2> pyramids;
    int current = 0;
    std::vector<std::uint64_t> ids;
    std::vector<Eigen::Vector2f> points;
    // Each point's templates in the current image (all levels), in a pool of fixed slots. The
    // backward track of one frame builds exactly the templates the next frame's forward track needs,
    // so a kept point takes over its backward slot instead of rebuilding.
    std::vector<int> slots;
    std::vector<PatchTemplate> pool;
    std::vector<int> free_slots;
    // Per slot, how many of its levels (from level 0) hold templates. A round-trip check builds only
    // the levels it runs on; the coarser ones are built when a track first needs them
    // (trackedTemplates), at the point's position in its image, which is prev() by then. A
    // motion-vector guess runs on the finest levels only (prior_pyramid_levels), so in the modes
    // that track from the vector most points never need them.
    std::vector<int> built_levels;
    int num_levels = 0;
    IFrameBridge bridge;  // chooses the motion prior, carrying P-frame vectors over I-frames
    // retry_previous_flow: the median displacement of the last temporal step's kept tracks (zero
    // before any), and whether a step has measured it since the start or the last reset(). Until one
    // has, a retry starts from the whole image's shift (shift_search) instead.
    Eigen::Vector2f previous_flow = Eigen::Vector2f::Zero();
    bool flow_known = false;
    ImageShiftSearch shift_search;
    // This frame's prior field (beginCamera) and whether it was bridged from an earlier P-frame.
    const MotionField* field = nullptr;
    bool field_bridged = false;
    // The temporal step's shares, and the step joined (the retry decides its candidates there). Its
    // traces and guess distances are the frame's for this camera, its guess distances appended to
    // the stats by endFrame (left camera first): the cameras may be tracked concurrently.
    std::array<TemporalPart, 2> parts;
    TemporalPart step;
    const ImagePyramid& cur() const { return pyramids[static_cast<std::size_t>(current)]; }
    const ImagePyramid& prev() const { return pyramids[static_cast<std::size_t>(1 - current)]; }
    std::span<PatchTemplate> slot(int index) {
      return {pool.data() + static_cast<std::ptrdiff_t>(index) * num_levels, static_cast<std::size_t>(num_levels)};
    }
    int acquire() {
      const int index = free_slots.back();
      free_slots.pop_back();
      return index;
    }
    void release(int index) { free_slots.push_back(index); }
    // Appends a point detected in cur() with the templates of every level in a fresh slot, and
    // returns the slot.
    int addDetected(std::uint64_t id, const Eigen::Vector2f& px, const PatchPattern& pattern) {
      const int index = acquire();
      buildPyramidPatch(cur(), px, pattern, slot(index));
      built_levels[static_cast<std::size_t>(index)] = num_levels;
      ids.push_back(id);
      points.push_back(px);
      slots.push_back(index);
      return index;
    }
    // The first `levels` templates of a slot, the missing ones built at px in `pyramid` first.
    std::span<const PatchTemplate> trackedTemplates(int index, const ImagePyramid& pyramid, const Eigen::Vector2f& px,
                                                    int levels, const PatchPattern& pattern) {
      int& built = built_levels[static_cast<std::size_t>(index)];
      const std::span<PatchTemplate> templates = slot(index).first(static_cast<std::size_t>(levels));
      if (built < levels) {
        buildPyramidPatch(pyramid, px, pattern, templates, static_cast<std::size_t>(built));
        built = levels;
      }
      return templates;
    }
    void resetSlots();
    // Keeps, in order, the points for which keep(index, kept_so_far) is true and frees the others'
    // slots (a slot below zero holds none). keep may read the points already kept: they sit at
    // [0, kept_so_far).
    template <class Keep>
    void retain(Keep keep) {
      std::size_t out = 0;
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (!keep(i, out)) {
          if (slots[i] >= 0) release(slots[i]);
          continue;
        }
        ids[out] = ids[i];
        points[out] = points[i];
        slots[out] = slots[i];
        ++out;
      }
      ids.resize(out);
      points.resize(out);
      slots.resize(out);
    }
  };

  // Forward-backward tracking from `from` to `to` with a flow guess on the finest `levels` pyramid
  // levels; true and the converged position when both directions converge and the round trip returns
  // within max_recovered_dist2 (squared px). `forward` holds the templates of p in `from` (shared by all
  // guesses of one point); slot `backward_slot` of `owner` receives the templates at the result in
  // `to`, on the levels the round trip runs on (built_levels).
  bool trackChecked(std::span<const PatchTemplate> forward, const ImagePyramid& from, const ImagePyramid& to,
                    const Eigen::Vector2f& p, const Eigen::Vector2f& flow_guess, int levels, float max_recovered_dist2,
                    CameraState& owner, int backward_slot, Eigen::Vector2f& result) const;
  // The two halves of trackChecked: the forward track alone, and the round-trip check of its result.
  // fine_start: where the forward track's levels below backward_levels_ started (p + flow_guess when
  // the check runs on every level the forward track ran on).
  bool trackForward(std::span<const PatchTemplate> forward, const ImagePyramid& to, const Eigen::Vector2f& p,
                    const Eigen::Vector2f& flow_guess, int levels, Eigen::Vector2f& tracked,
                    Eigen::Vector2f& fine_start) const;
  bool checkBackward(const ImagePyramid& from, const ImagePyramid& to, const Eigen::Vector2f& p,
                     const Eigen::Vector2f& tracked, const Eigen::Vector2f& flow_guess,
                     const Eigen::Vector2f& fine_start, int levels, float max_recovered_dist2, CameraState& owner,
                     int backward_slot) const;
  const MotionField* priorField(int camera, const DecodedStereoFrame& input, FrontendStats& stats);
  // thin_when_full_px: drops the younger of two left tracks too close together, in both cameras.
  void thinTracks(FrontendStats& stats);
  // The statistics and the image flow of a point the temporal step kept at tracked.
  void countKept(TemporalPart& out, const Eigen::Vector2f& tracked, const PointTrace& trace) const;
  // retry_previous_flow on the points every guess lost (cam.step), when they are enough of the
  // frame's (retry_min_lost_fraction); the others are lost and get slot -1. True when any was lost.
  bool retryFromPreviousFlow(CameraState& cam);
  // The codec-confidence checks of the config's prior_* keys on the vector found at p.
  bool trustVector(const MotionBlock& block, const CameraState& cam, const Eigen::Vector2f& p) const;
  void detectAndMatch(const DecodedStereoFrame& input, FrontendStats& stats);
  // Where the left point p is first looked for in the right image (the config's matching_guess).
  Eigen::Vector2f stereoGuess(const Eigen::Vector2f& p) const;
  // stereo_rematch: matches the left tracks that have no right view to the right image again.
  void rematchStereo(FrontendStats& stats);
  void detectRightOnly(const DecodedStereoFrame& input, FrontendStats& stats);
  // Right-image grid cells that the left camera sees (blocked for right-only detection).
  void computeRightOverlap(const StereoRig& rig);
  void filterEpipolar(FrontendStats& stats);

  FrontendConfig config_;
  const PatchPattern* pattern_ = nullptr;
  AlignParams align_;
  int num_levels_ = 0;
  int prior_levels_ = 0;     // levels a motion-vector guess is tracked on (prior_pyramid_levels + 1)
  int backward_levels_ = 0;  // at most this many levels in a round-trip check (backward_pyramid_levels + 1)
  // Round-trip tolerances (squared px): a temporal track's, and the left-to-right match's.
  float temporal_round_trip2_ = 0.f;
  float stereo_round_trip2_ = 0.f;
  int max_points_ = 0;
  int width_ = 0, height_ = 0;
  std::array<GenericCamera<double>, 2> cameras_model_;
  SE3d T_cam1_cam0_;
  Eigen::Matrix3d essential_;  // f0^T E f1 = 0 for unit bearings f0 (cam0), f1 (cam1)
  double average_depth_m_ = 0.0;
  DetectorParams detector_params_;
  DetectorParams right_detector_params_;     // safe radius around the right camera's principal point
  std::vector<std::uint8_t> right_overlap_;  // per right-image cell, non-zero: the left camera sees it
  GridDetector detector_;
  std::vector<Eigen::Vector2f> new_points_;
  // thinTracks: a grid of cells (thin_when_full_px / 2 wide, so a cell holds at most one kept
  // point) with each kept point's index or -1, and the ids dropped in one call.
  std::vector<int> thin_grid_;
  int thin_cols_ = 0, thin_rows_ = 0;
  float thin_cell_px_ = 0.f;
  std::vector<std::uint64_t> thinned_ids_;
  // rematchStereo: the tracks found again, then the right camera's lists merged with them in id order.
  std::vector<std::uint64_t> rematch_ids_, merged_ids_;
  std::vector<Eigen::Vector2f> rematch_points_, merged_points_;
  std::vector<int> rematch_slots_, merged_slots_;
  std::array<CameraState, 2> cameras_;
  std::uint64_t next_track_id_ = 1;
  bool have_previous_ = false;
  bool retry_flow_ = false;  // retry_previous_flow applies to the frame being tracked (its InputScope)
  bool presmooth_ = false;   // presmooth applies to the frame being tracked
  std::chrono::steady_clock::time_point frame_start_;  // when beginFrame started (FrontendStats::time_ms)
};

}  // namespace voca
