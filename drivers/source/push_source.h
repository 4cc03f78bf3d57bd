#pragma once
// Frames handed in by a program (the library API) instead of read from a device or a file. A fixed
// ring of frame buffers lies between the caller's thread, which pushes, and the pipeline's source
// thread, which takes the frames in order: nothing is allocated per frame after construction (a
// packet larger than any before grows its buffer once). Offline, a push waits for room, so every
// frame is processed; live, a push never waits: a frame with no room is dropped and counted as lost
// (the pipeline sees the gap in the frame indices).

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "drivers/source/stereo_source.h"

namespace voca {

struct PushSourceOptions {
  SourceKind kind = SourceKind::kEncoded;  // kEncoded: H.264 access units; kRaw: gray images
  int width = 0, height = 0;               // every frame's size (the calibration's)
  int capacity = 4;                        // frames that may wait between push and the pipeline
  bool live = false;
  double nominal_rate_hz = 0.0;  // 0 when unknown
  std::string description = "pushed frames";
};

class PushSource final : public StereoSource {
 public:
  explicit PushSource(const PushSourceOptions& options);
  ~PushSource() override;

  const SourceInfo& info() const override { return info_; }
  // Pipeline side: waits for the next pushed frame; false once close()d and drained, or interrupted.
  bool next(RawStereoFrame& frame) override;
  bool next(EncodedStereoPacket& packet) override;
  void interrupt() override;
  SourceCounters counters() const override;

  // Caller side, one thread. Copy the frame in and return true; false when the live policy dropped it
  // (no room) or the source was interrupted or closed. Throw InputError, keeping the source usable,
  // for a time not after the previous frame's, an empty packet or an image of another size.
  bool pushEncoded(std::int64_t t_ns, std::span<const std::uint8_t> left, std::span<const std::uint8_t> right);
  bool pushRaw(std::int64_t t_ns, std::array<ImageView<const std::uint8_t>, 2> images);
  // No more frames: next() returns false once the frames pushed before are taken.
  void close();
  // Drops the frames waiting (a stop that discards them); they count as lost.
  void discardWaiting();

 private:
  struct Impl;
  // Checks a frame's time against the previous one's and gives it its index.
  std::int64_t admit(std::int64_t t_ns);
  // A free buffer to fill, -1 when the frame is to be dropped (live, none free) or pushing ended.
  int acquireFree();

  std::unique_ptr<Impl> impl_;
  SourceInfo info_;
  bool live_;
  std::int64_t next_index_ = 0;
  std::int64_t last_t_ns_ = 0;
  bool have_last_ = false;
  std::atomic<bool> interrupted_{false};
  std::atomic<bool> closed_{false};
  std::atomic<std::int64_t> lost_{0};
};

}  // namespace voca
