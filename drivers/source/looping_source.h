#pragma once
// A VOCA video folder replayed over and over, for soak tests of the live pipeline: an endless camera
// made from a short recording. Each pass continues the last one's clock (timestamps and packet pts
// keep increasing), so the pipeline sees one long stream; at the seam the scene jumps back to the
// recording's start, which the tracker may take as a reset. Seeded faults stand in for a bad link:
// a frame dropped (both cameras' packets lost) and a packet damaged (its slice data overwritten with
// noise, so the real decoder sees bad data and conceals it). After a drop the source resumes at the
// next keyframe of both cameras, as the network source does, so the decoders never see a reference
// missing; a short GOP in the recording keeps such losses short.
//
// The recording is read into memory once; after that next() copies packets into the caller's
// reused buffers and allocates nothing.

#include <array>
#include <atomic>
#include <cstdint>
#include <random>
#include <vector>

#include "drivers/source/stereo_source.h"
#include "formats/dataset/dataset.h"

namespace voca {

struct LoopOptions {
  std::int64_t frames = 0;   // frames to deliver or lose in all (frame indices 0..frames-1); 0: without end
  double drop_rate = 0.0;    // chance per frame that it is dropped, [0, 1)
  double damage_rate = 0.0;  // chance per frame that one camera's packet is damaged, [0, 1)
  std::uint64_t seed = 1;
};

// What the source did to the stream so far (read any time, from any thread).
struct LoopCounters {
  std::int64_t frames = 0;           // frame indices given out: delivered + dropped + skipped
  std::int64_t delivered = 0;        // frames handed to the pipeline
  std::int64_t dropped = 0;          // frames dropped at random
  std::int64_t skipped = 0;          // frames lost after a drop, waiting for the next keyframe
  std::int64_t damaged_packets = 0;  // delivered frames with one camera's packet damaged
  std::int64_t passes = 0;           // times the recording began (1 on the first frame)
};

class LoopingVideoSource final : public StereoSource {
 public:
  // dataset must be a video folder whose first frame is a keyframe of both cameras. Throws
  // InputError for anything else, for rates outside [0, 1) and for a recording of fewer than two
  // frames.
  LoopingVideoSource(const Dataset& dataset, const LoopOptions& options);

  const SourceInfo& info() const override { return info_; }
  bool next(EncodedStereoPacket& packet) override;
  void interrupt() override { interrupted_ = true; }
  // frames_lost: dropped and skipped frames (the gaps in frame_index).
  SourceCounters counters() const override;

  LoopCounters loopCounters() const;
  // Frames in one pass of the recording.
  std::int64_t framesPerPass() const { return static_cast<std::int64_t>(recording_.size()); }

 private:
  // Advances to the next frame index and recording position; false when the run's frames are used up.
  bool advance();
  void damage(decode::Packet& packet);

  LoopOptions options_;
  SourceInfo info_;
  std::vector<EncodedStereoPacket> recording_;  // one pass, pristine
  std::int64_t pass_period_ns_ = 0;             // sensor time from a pass's first frame to the next pass's
  std::array<std::int64_t, 2> pass_period_pts_{};
  std::mt19937_64 random_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::int64_t next_index_ = 0;  // frame index the next frame gets
  bool waiting_for_keyframe_ = false;
  std::atomic<bool> interrupted_{false};
  std::atomic<std::int64_t> delivered_{0}, dropped_{0}, skipped_{0}, damaged_packets_{0}, frames_{0};
};

}  // namespace voca
