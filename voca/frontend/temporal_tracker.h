#pragma once
// Temporal tracking of one camera: each track from the previous image into the current one, from the
// guesses its prior mode chooses (the previous position, the codec's motion vector), each checked by
// a round trip, merged as the mode says; the last resort, decided once the frame is known, a retry
// from the image's previous flow.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "voca/frontend/frontend_config.h"
#include "voca/frontend/frontend_stats.h"
#include "voca/frontend/image_shift.h"
#include "voca/frontend/round_trip.h"
#include "voca/frontend/track_store.h"
#include "voca/motion/motion_field.h"

namespace voca {

// What the temporal step made of a run of one camera's points, in their order: the next frame's
// points (ids, positions, template slots; a retry candidate holds slot -1 until decided), the traces,
// the retry candidates, the kept tracks' flow and guess distances, the counters. Each share of a step
// has one, with scratch slots of its own; the joined step has one more.
struct TemporalShare {
  // A point every guess lost, held for the retry decision.
  struct RetryCandidate {
    std::size_t next = 0;   // its place in the next frame's lists
    std::size_t trace = 0;  // index into the traces
    int slot = 0;           // the point's templates
  };
  TemporalStats stats;
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector2f> points;
  std::vector<int> slots;
  std::vector<PointTrace> traces;
  std::vector<RetryCandidate> retry_candidates;
  std::vector<float> flow_x, flow_y;
  std::vector<float> guess_dist_plain_px, guess_dist_prior_px;
  FreeSlots free_slots;

  void reserve(std::size_t max_points, std::size_t scratch_slots);
  void clear();
  // Appends another share's results after this one's (its indices shifted to match).
  void append(const TemporalShare& other);
};

class TemporalTracker {
 public:
  // A step's points may be split into this many shares, tracked concurrently.
  static constexpr int kShares = 2;
  // Scratch slots per share: a point's plain and prior backward tracks. A point takes two fresh
  // slots and gives back at least as many, so two suffice.
  static constexpr int kScratchSlotsPerShare = 2;
  // What the camera's TemplateSlots need beyond one slot per point.
  static constexpr int kScratchSlots = kShares * kScratchSlotsPerShare;

  TemporalTracker() = default;
  // camera: sized for the largest image (its pyramids size the whole-image shift search).
  TemporalTracker(const FrontendConfig& config, const RoundTripTracker& klt, int max_points, int max_width,
                  int max_height, const CameraTracks& camera);

  // Starts a frame whose image camera.advance() has just added: chooses the prior field (`motion`,
  // nullptr when the frame has none), bridged over I-frames, and, when `following` (there was a
  // previous frame), hands each share its scratch slots. retry_previous_flow: whether that last
  // resort applies to this frame.
  void begin(const MotionField* motion, int frames_missing_before, bool following, bool retry_previous_flow,
             CameraTracks& camera);
  // Tracks camera's points [begin, end) into `share`. Shares of one step may run concurrently: each
  // writes only its own results and its points' template slots.
  void trackShare(int share, std::size_t begin, std::size_t end, CameraTracks& camera);
  // Joins the shares in the points' order, runs the retry and makes the step's points the camera's
  // tracks (the ids still ascending).
  void finish(CameraTracks& camera);
  // Forgets the motion remembered across frames (the flow, the bridged field) and the last step.
  void reset();

  // The last step's results: its counters, whether its prior was bridged over an I-frame, a trace
  // per point, and the guess distances of FrontendStats.
  const TemporalStats& stats() const { return step_.stats; }
  bool bridged() const { return field_bridged_; }
  std::span<const PointTrace> traces() const { return step_.traces; }
  std::span<const float> guessDistPlain() const { return step_.guess_dist_plain_px; }
  std::span<const float> guessDistPrior() const { return step_.guess_dist_prior_px; }

 private:
  // The statistics and the image flow of a point the step kept at tracked.
  void countKept(TemporalShare& out, const Eigen::Vector2f& tracked, const PointTrace& trace) const;
  // retry_previous_flow on the points every guess lost (step_), when they are enough of the frame's
  // (retry_min_lost_fraction); the others are lost and get slot -1. True when any was lost.
  bool retryFromPreviousFlow(CameraTracks& camera);
  // The codec-confidence checks of the config's prior_* keys on the vector found at p.
  bool trustVector(const MotionBlock& block, const CameraTracks& camera, const Eigen::Vector2f& p) const;

  FrontendConfig config_;
  RoundTripTracker klt_;
  int num_levels_ = 0;
  int prior_levels_ = 0;      // levels a motion-vector guess is tracked on (prior_pyramid_levels + 1)
  float round_trip2_ = 0.f;   // max_recovered_dist2_px2
  MotionPriorBridge bridge_;  // chooses the motion prior, carrying P-frame vectors over I-frames
  // retry_previous_flow: the median displacement of the last step's kept tracks (zero before any),
  // and whether a step has measured it since the start or the last reset(). Until one has, a retry
  // starts from the whole image's shift (shift_search_) instead.
  Eigen::Vector2f previous_flow_ = Eigen::Vector2f::Zero();
  bool flow_known_ = false;
  ImageShiftSearch shift_search_;
  // This frame's (begin).
  const MotionField* field_ = nullptr;
  bool field_bridged_ = false;
  bool following_ = false;
  bool retry_flow_ = false;
  std::array<TemporalShare, kShares> shares_;
  TemporalShare step_;
};

}  // namespace voca
