#pragma once
// A stereo stream received over the network (`voca run udp://127.0.0.1:5000`): the MPEG-TS that
// `voca stream` sends (drivers/network/ts_writer.h), demuxed with libavformat as it arrives. Each
// camera's access units carry their sensor stamp (drivers/network/frame_stamp.h); the two cameras
// are paired by that stamp and handed to the pipeline's decode stage as they complete.
//
// Loss: an access unit that arrived damaged (the demuxer saw TS packets missing) or without a stamp
// is dropped, and so is its partner; a frame of one camera whose partner never came is counted as
// unpaired. After any gap the source resumes at the next keyframe of both cameras, so the decoders
// only ever see a complete stream (no concealed pictures feeding the VO); every frame of the
// sender's counter not handed on after the first is counted as lost. The sender's GOP bounds how
// long a loss lasts.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "drivers/source/stereo_source.h"

namespace voca {

struct NetworkSourceOptions {
  double start_timeout_s = 30.0;  // waiting for the stream to begin
  double timeout_s = 3.0;         // no data for this long once started = the sender has stopped
  // Polled while waiting (e.g. SIGINT): true ends the wait like interrupt() does.
  std::function<bool()> stop_requested;
  std::int64_t max_frames = 0;  // end after this many tracked stereo frames (0: when the stream does)
  // A recording started later (`--start-frame`): the pairs before this sender frame index are
  // decoded (later frames reference them) but not tracked (SourceInfo::first_tracked_frame).
  std::int64_t first_frame = 0;
  // Stop at the first frame lost or damaged (next() throws InputError naming it) instead of counting
  // it and resuming at the next keyframe: `--strict`, e.g. to check that a recording is whole.
  bool strict = false;
};

// True for input names libavformat opens as a network stream (udp://, tcp://, rtp://, srt://, ...).
bool isStreamUrl(const std::string& input);

// A stream recorded to a file (`voca stream <dataset> out.ts`) is replayed from a file:// URL. It is
// not live: the file is read as fast as the pipeline takes frames, so every frame is tracked, as
// from a dataset folder (`--realtime` paces it at its stamps instead).
bool isRecordedStreamUrl(const std::string& url);

// The file a recording's file:// URL names, as libavformat's file protocol opens it.
std::filesystem::path recordedStreamFile(const std::string& url);

// The file:// URL of `path` when it is a regular file that starts like an MPEG-TS (a sync byte
// every 188 bytes), nullopt otherwise.
std::optional<std::string> recordedStreamUrl(const std::filesystem::path& path);

class NetworkStereoSource : public StereoSource {
 public:
  // Opens the URL and waits (up to start_timeout_s, or until interrupt()) until both cameras'
  // streams are known. Throws InputError when no VOCA stereo stream arrives in that time (a
  // recording: when the file holds none) or the stream is not two H.264 cameras of one size.
  explicit NetworkStereoSource(const std::string& url, const NetworkSourceOptions& options = {});
  ~NetworkStereoSource() override;

  const SourceInfo& info() const override { return info_; }
  // Blocks until the next pair is complete; false when the stream has ended (no data for
  // timeout_s) or after interrupt(). Strict: throws InputError at the first loss.
  bool next(EncodedStereoPacket& packet) override;
  void interrupt() override { interrupted_ = true; }
  SourceCounters counters() const override;

  // Why next() returned false ("interrupted", "no data for 3 s", a libavformat error), or empty.
  const std::string& endReason() const { return end_reason_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  SourceInfo info_;
  std::atomic<bool> interrupted_{false};
  std::atomic<std::int64_t> frames_lost_{0}, unpaired_{0};
  std::string end_reason_;
};

}  // namespace voca
