#pragma once
// Choosing a decoder: hardware for pixels when a device is there (plus a software parse for
// the motion vectors), software otherwise. The choice is a pure function of a device probe so it can
// be tested without devices.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/decode/demuxer.h"

namespace voca::decode {

enum class DecoderKind { kAuto, kSoftware, kVaapi, kV4l2m2m };

const char* decoderKindName(DecoderKind kind);
// Parses "auto", "software", "vaapi", "v4l2m2m"; throws InputError naming the accepted values.
DecoderKind parseDecoderKind(std::string_view text);

// What the machine offers. Each function answers for one decoder kind; the system probe really opens
// the device, a test injects answers.
struct DecoderProbe {
  // The VAAPI render node exists.
  std::function<bool(const std::string& device)> vaapi_device_present;
  // A VAAPI device can be created on it and libavcodec can decode `codec` with it.
  std::function<bool(const std::string& device, VideoCodec codec)> vaapi_open;
  // A V4L2 memory-to-memory decoder for `codec` is built into libavcodec and a /dev/video node is an
  // M2M device that takes `codec` on its OUTPUT queue (VIDIOC_QUERYCAP / VIDIOC_ENUM_FMT).
  std::function<bool(VideoCodec codec)> v4l2m2m_present;
};

// The probe of this machine.
DecoderProbe systemDecoderProbe();

// The outcome: the decoder kind to use, the one-line description to log ("decoder: software",
// "decoder: vaapi (+ software MV parse)") and why hardware was not taken.
struct DecoderChoice {
  DecoderKind kind = DecoderKind::kSoftware;
  std::string description;
  std::vector<std::string> notes;
};

// kAuto tries VAAPI, then V4L2 M2M, then software. An explicitly requested hardware decoder that is
// not usable throws voca::InputError saying why (the user asked for it; silently decoding in
// software would hide a misconfiguration). Software needs no probe.
DecoderChoice selectDecoderKind(DecoderKind requested, VideoCodec codec, const std::string& vaapi_device,
                                bool export_motion, const DecoderProbe& probe);

// "decoder: <kind>[ (+ software MV parse)]".
std::string describeDecoder(DecoderKind kind, bool export_motion);

}  // namespace voca::decode
