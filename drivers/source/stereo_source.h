#pragma once
// Where stereo frames come from: one interface for dataset replay, video folders, live cameras and
// network streams. A source delivers either raw gray images (cameras, image datasets) or one
// compressed access unit per camera (video files, network streams); the pipeline encodes or
// decodes as needed. The source stamps each frame's sensor time and index once; later stages never
// rewrite them.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/decode/demuxer.h"
#include "voca/core/image.h"

namespace voca {

// Two gray images taken together (DESIGN.md section 2, "RawStereoFrame").
struct RawStereoFrame {
  std::int64_t t_ns = 0;            // sensor time: capture timestamp or the dataset's
  std::int64_t frame_index = 0;     // position in the source from 0; a gap means the source lost frames
  std::array<GrayImage, 2> images;  // cam0 (left), cam1 (right)
  // The source could not read this frame's images (non-strict replay of an image dataset): t_ns and
  // frame_index are set, the images are not. The pipeline skips it and counts it as damaged, as it
  // does a video frame that cannot be decoded.
  bool damaged = false;
};

// One compressed access unit per camera, in decode order (DESIGN.md section 2, "EncodedStereoPacket").
struct EncodedStereoPacket {
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  std::array<decode::Packet, 2> packets;  // buffers are reused between frames
};

enum class SourceKind : std::uint8_t {
  kRaw,      // next(RawStereoFrame&)
  kEncoded,  // next(EncodedStereoPacket&); info().streams describe the two streams
};

// What a source is, fixed once it is open.
struct SourceInfo {
  SourceKind kind = SourceKind::kRaw;
  std::string description;           // one line for logs, e.g. "video folder seq-500k (2x 752x480 h264)"
  int width = 0, height = 0;         // image size of each camera
  std::int64_t expected_frames = 0;  // frames to track; 0 when unknown (live input)
  // kEncoded replay from a later frame: frames before this index are delivered so the decoder has
  // their references, but are not tracked (the decode stage lets them go).
  std::int64_t first_tracked_frame = 0;
  // Frames arrive at the sensor's pace whether or not anyone is ready (cameras, network): the
  // pipeline drops the oldest waiting frame instead of making the source wait.
  bool live = false;
  double nominal_rate_hz = 0.0;               // 0 when unknown
  std::array<decode::StreamInfo, 2> streams;  // kEncoded only
  std::array<std::string, 2> stream_names;    // kEncoded: each camera's stream in messages (file, URL)
};

// What went wrong at the source without stopping it (live input).
struct SourceCounters {
  std::int64_t frames_lost = 0;  // the device or the network lost them (gaps in frame_index)
  std::int64_t unpaired = 0;     // a frame of one camera with no partner from the other
};

// A pull source. next() is called from one thread (the pipeline's source stage); interrupt() may
// be called from any thread and makes a blocking next() return false soon.
class StereoSource {
 public:
  virtual ~StereoSource() = default;

  virtual const SourceInfo& info() const = 0;

  // The next frame into the caller's buffers (sized on first use, reused afterwards); false at the
  // end of the input or after interrupt(). Only the call matching info().kind is valid; the other
  // throws std::logic_error. Errors throw voca::InputError (bad data, naming the file and frame)
  // or voca::RuntimeFailure (device failure).
  virtual bool next(RawStereoFrame& frame);
  virtual bool next(EncodedStereoPacket& packet);

  virtual void interrupt() {}
  virtual SourceCounters counters() const { return {}; }
  // Problems that did not stop the source (frames skipped as damaged, a video that ended early, a
  // device's notes), for the run's summary; read after the input ends.
  virtual std::vector<std::string> warnings() const { return {}; }
};

}  // namespace voca
