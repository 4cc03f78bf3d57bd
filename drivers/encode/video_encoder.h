#pragma once
// Gray frames -> compressed video with libavcodec, frame by frame: live capture (in software or on
// the device's hardware encoder) and each pass of a file encoding (video_file_encoder.h).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "voca/core/image.h"

struct AVCodecContext;

namespace voca::encode {

// The x264 options of the paper (supplementary "Video Encoding"): no B-frames so the stream is
// causal, one reference frame, a keyframe at most every 1000 frames.
inline constexpr const char* kPaperX264Params =
    "partitions=p8x8,p4x4,i8x8:keyint=1000:me=umh:merange=64:subme=6:bframes=0:ref=1";

// How to encode: codec (libx264, mpeg4, mpeg2video; for live encoding also the hardware H.264
// encoders h264_v4l2m2m and h264_vaapi), target bitrate, frame rate and rate control.
struct EncoderSettings {
  std::string codec = "libx264";
  std::int64_t bitrate_bps = 500000;
  int fps_num = 30, fps_den = 1;  // the official VOCA code encodes at 30 fps whatever the dataset rate
  std::string x264_params = kPaperX264Params;
  bool two_pass = true;                // file encoding only; the live encoder is always one pass
  std::string x264_preset = "medium";  // the ffmpeg CLI default, which the paper used
  std::string x264_tune;               // e.g. "zerolatency" for live capture; empty = none
  int gop_size = 600;  // mpeg4 / mpeg2video: max frames between keyframes (libx264 takes keyint from x264_params)
  // Encoder threads; 0 = the codec's automatic choice. One by default: x264's output then does not
  // depend on the machine's core count (reproducible videos), and x264's frame threads stall under
  // qemu-user emulation, where cross-built tests run.
  int threads = 1;
  bool global_header = false;  // codec headers out of band (extradata) as .mp4 needs; in band for raw streams
  // Live streaming: hold the rate at bitrate_bps over about a second (VBV / hardware CBR) instead of
  // averaging it over the whole video.
  bool constant_bitrate = false;
  std::string vaapi_device = "/dev/dri/renderD128";  // h264_vaapi only: the render node
  // libx264 only: code luma alone (4:0:0, High profile) instead of 4:2:0 with neutral chroma. The
  // cameras are monochrome, so the bits hardly change, but a decoder then has no chroma planes to
  // reconstruct (about a tenth of a software decode). Off by default: the paper coded yuv420p,
  // and hardware decoders commonly take 4:2:0 only. Odd frame sizes are always coded 4:0:0.
  bool monochrome = false;
};

// True for the encoders that run on a device (h264_v4l2m2m, h264_vaapi): single pass only.
bool isHardwareEncoder(std::string_view codec);

// Limits libav's console messages to errors (libx264 prints its statistics at info level).
void silenceCodecLogs();

// Parses "500k", "1M", "1.5M", "1000000" (bits per second; k = 1000, M = 1000000).
// Throws InputError on anything else, including zero and negative rates.
std::int64_t parseBitrate(std::string_view text);

// The one spelling of a rate in labels, folder and file names: kilobits when whole ("250k", "500k",
// "1000k", so a table of rates reads in one unit), else bits per second. parseBitrate reads it back.
std::string bitrateLabel(std::int64_t bps);

// One compressed access unit. pts/dts are in frames at the encoder's frame rate.
struct EncodedPacket {
  std::vector<std::uint8_t> bytes;
  std::int64_t pts = 0;
  std::int64_t dts = 0;
  bool keyframe = false;
};

// Which pass an encoder instance runs. Two-pass rate control runs the whole sequence through a
// kFirst encoder (statistics only) and then through a kSecond encoder reading those statistics.
enum class EncoderPass { kSingle, kFirst, kSecond };

// A frame-by-frame encoder for 8-bit gray frames. The luma plane carries the gray values
// unchanged (full range, signalled in the stream) and chroma is a constant 128, so a decoder's
// Y plane returns the original intensities up to compression loss. Every size from 16x16 up is
// coded exactly, odd ones included (libx264 then codes 4:0:0, whose crop window has one-pixel
// units, so decoders return the original size). Packet buffers are reused between calls.
class VideoEncoder {
 public:
  VideoEncoder();
  ~VideoEncoder();
  VideoEncoder(VideoEncoder&&) noexcept;
  VideoEncoder& operator=(VideoEncoder&&) noexcept;
  VideoEncoder(const VideoEncoder&) = delete;
  VideoEncoder& operator=(const VideoEncoder&) = delete;

  // Opens the codec for frames of width x height. stats_file is required for kFirst/kSecond:
  // pass 1 writes it (libx264 writes its own stats file, and its .mbtree beside it), pass 2 reads it.
  // Throws InputError for an unknown codec or invalid settings, RuntimeFailure when libavcodec fails.
  void open(const EncoderSettings& settings, int width, int height, EncoderPass pass = EncoderPass::kSingle,
            const std::filesystem::path& stats_file = {});

  // Encodes one frame with presentation time pts (in frames). Returns the packets that came out
  // (zero or more: encoders with lookahead hold frames back); valid until the next call.
  // Throws InputError when the frame size differs from the size given to open().
  std::span<const EncodedPacket> encode(GrayView frame, std::int64_t pts);

  // Drains the frames held back. After flush() the encoder must be re-opened to encode again.
  std::span<const EncodedPacket> flush();

  bool isOpen() const;
  int width() const;  // coded size = the frames' size
  int height() const;
  const EncoderSettings& settings() const;
  // For muxers: the codec context (codec parameters, global headers). Null before open().
  const AVCodecContext* codecContext() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::encode
