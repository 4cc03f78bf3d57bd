#pragma once
// The live encoder: gray frames -> H.264 for streaming and recording, one packet out per frame in
// (no B-frames, one reference frame, no look-ahead, a long GOP, constant bitrate). It runs on the
// device's hardware encoder when there is one (V4L2 memory-to-memory on Jetson / RK3588 / Raspberry
// Pi, VAAPI on Intel and AMD) and on libx264 otherwise. The choice of encoder lives here and only
// here; `voca stream` and `voca record` take an EncoderKind and LiveEncoderSettings.

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/encode/video_encoder.h"

namespace voca::encode {

enum class EncoderKind { kAuto, kX264, kV4l2m2m, kVaapi };

const char* encoderKindName(EncoderKind kind);  // "auto", "x264", "v4l2m2m", "vaapi"
// Parses the names above; throws InputError naming the accepted values.
EncoderKind parseEncoderKind(std::string_view text);
// The libavcodec encoder of a concrete kind: libx264, h264_v4l2m2m, h264_vaapi.
const char* encoderCodecName(EncoderKind kind);

struct LiveEncoderSettings {
  EncoderKind kind = EncoderKind::kAuto;
  std::int64_t bitrate_bps = 1000000;
  int fps_num = 20, fps_den = 1;  // the camera's rate: rate control spends bitrate_bps / fps per frame
  // Frames between keyframes: long (bits go to P-frames, whose vectors the VO uses) but short enough
  // that a receiver that lost a packet or joined late recovers within a few seconds.
  int gop = 120;
  std::string vaapi_device = "/dev/dri/renderD128";
  // SPS/PPS out of band, as an .mp4 needs (`voca record`); false: in band, repeated at each keyframe,
  // as a stream needs (`voca stream`).
  bool global_header = false;
  // Luma alone (4:0:0): x264 only, so auto then skips the hardware encoders, which code 4:2:0.
  bool monochrome = false;
};

// Sets fps_num/fps_den from a rate in Hz (exact to 1/1000 Hz: 29.97 -> 29970/1000). Throws InputError
// unless 0 < fps_hz <= 1000.
void setFrameRate(LiveEncoderSettings& live, double fps_hz);

// The x264 options of a causal, zero-delay stream: no B-frames, one reference, no look-ahead
// (rc-lookahead and sync-lookahead 0, and force-cfr: x264's variable-frame-rate input mode holds one
// frame back to learn its duration), keyframes every `gop` frames.
std::string lowLatencyX264Params(int gop);

// The EncoderSettings a concrete kind (not kAuto) is opened with.
EncoderSettings lowLatencySettings(EncoderKind kind, const LiveEncoderSettings& live);

// What the machine offers, answered without opening an encoder; a test injects its own answers.
struct EncoderProbe {
  std::function<bool()> v4l2m2m_present;                         // an M2M node that encodes H.264
  std::function<bool(const std::string& device)> vaapi_present;  // the render node exists
};
EncoderProbe systemEncoderProbe();

// Opens one concrete kind (throws InputError / RuntimeFailure when it cannot). Injected by tests.
using EncoderOpener = std::function<void(EncoderKind kind)>;

struct EncoderChoice {
  EncoderKind kind = EncoderKind::kX264;
  std::string description;         // "encoder: x264 (libx264, 1000 kbit/s, GOP 120)"
  std::vector<std::string> notes;  // why the kinds before it were not taken
};

// kAuto tries V4L2 M2M, then VAAPI, then x264, and takes the first whose device is present and
// that opens. An explicit kind that is missing or fails to open throws InputError saying why and
// what to use instead (asking for hardware and silently getting software would hide a misconfigured
// board).
EncoderChoice selectEncoder(const LiveEncoderSettings& live, const EncoderProbe& probe, const EncoderOpener& open);

// Opens `encoder` for width x height frames as selectEncoder chooses with the system probe.
EncoderChoice openLiveEncoder(VideoEncoder& encoder, const LiveEncoderSettings& live, int width, int height);

}  // namespace voca::encode
