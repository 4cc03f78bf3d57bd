#pragma once
// The sender of compress-then-analyze (`voca stream`): a raw stereo dataset replayed at the rate
// it was recorded, each camera encoded live with the low-latency encoder (drivers/encode/
// live_encoder.h), stamped with its sensor time and sent as MPEG-TS (drivers/network/ts_writer.h).
// What a robot's camera + hardware encoder would send, reproducible from a recording.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

#include "drivers/encode/live_encoder.h"

namespace voca::pipeline {

struct StreamOptions {
  std::filesystem::path input;           // a raw stereo dataset folder (EuRoC / TUM-VI / KITTI layout)
  std::string url;                       // udp://host:port, tcp://host:port or a .ts file
  encode::LiveEncoderSettings encoder;   // fps comes from the dataset
  double speed = 1.0;                    // playback speed factor (1 = the recording's own rate)
  int max_frames = 0;                    // 0 = all
  bool progress = true;                  // progress lines on stderr
  std::function<bool()> stop_requested;  // default: SIGINT/SIGTERM
};

struct StreamResult {
  std::string description;          // the input, one line
  std::string encoder_description;  // "encoder: x264 (libx264, 1000 kbit/s, GOP 120)"
  std::int64_t frames = 0;          // stereo pairs sent
  std::int64_t bytes = 0;           // video payload of both cameras
  double seconds = 0.0;             // wall time from the first frame to the last
  double recorded_seconds = 0.0;    // the recording time the frames sent span (frames / frame rate)
  double encode_ms_p50 = 0.0, encode_ms_p99 = 0.0, encode_ms_max = 0.0;  // both cameras, per pair
  std::int64_t late_frames = 0;  // pairs sent more than a frame period after their due time
  int stop_signal = 0;           // the signal that stopped the stream early (0: none)
};

// Throws InputError for bad input found before sending starts (not a raw dataset, bad URL,
// encoder unusable). Ends when the dataset does, max_frames are sent, or a stop is requested.
StreamResult runStream(const StreamOptions& options);

void printStreamSummary(const StreamResult& result, std::FILE* out);

}  // namespace voca::pipeline
