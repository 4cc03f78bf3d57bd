#pragma once
// Video files -> compressed packets (libavformat), with the stream parameters a decoder needs.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace voca::decode {

// Codecs whose decoders export motion vectors (DESIGN.md section 4); kOther decodes pixels only.
enum class VideoCodec { kH264, kMpeg4, kMpeg2, kOther };

const char* videoCodecName(VideoCodec codec);

inline constexpr std::int64_t kNoPts = std::numeric_limits<std::int64_t>::min();

// What a decoder needs to know about a stream, independent of the container.
struct StreamInfo {
  VideoCodec codec = VideoCodec::kOther;
  std::string codec_name;  // libavcodec's name, e.g. "h264"
  int width = 0, height = 0;
  std::vector<std::uint8_t> extradata;         // out-of-band codec headers (avcC, VOL), may be empty
  int time_base_num = 1, time_base_den = 1;    // unit of the packet pts
  int frame_rate_num = 0, frame_rate_den = 1;  // average frame rate, 0 when unknown
  bool constant_frame_rate = false;            // container says every frame lasts 1 / frame_rate
  std::int64_t num_frames = 0;                 // from the container index, 0 when unknown
};

// One compressed access unit in decode order; the buffers are reused between reads.
struct Packet {
  std::vector<std::uint8_t> bytes;
  std::int64_t pts = kNoPts;
  std::int64_t dts = kNoPts;
  bool keyframe = false;
  std::int64_t index = 0;  // position in the stream's decode order, from 0
};

// Reads the best video stream of a file. Errors (missing or unreadable file, no video stream,
// truncated or corrupt container) throw voca::InputError naming the file and the packet index.
class Demuxer {
 public:
  explicit Demuxer(const std::filesystem::path& path);
  ~Demuxer();
  Demuxer(const Demuxer&) = delete;
  Demuxer& operator=(const Demuxer&) = delete;

  const StreamInfo& stream() const { return info_; }
  const std::filesystem::path& path() const { return path_; }

  // The next packet of the video stream; false at the end of the file.
  bool read(Packet& packet);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::filesystem::path path_;
  StreamInfo info_;
  std::int64_t next_index_ = 0;
};

// Reads every packet of a file into memory (benchmarks, tests).
std::vector<Packet> readAllPackets(Demuxer& demuxer);

}  // namespace voca::decode
