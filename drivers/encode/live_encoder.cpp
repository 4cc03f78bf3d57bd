#include "drivers/encode/live_encoder.h"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <fmt/core.h>

extern "C" {
#include <libavcodec/avcodec.h>
}

#include "platform/v4l2/m2m_devices.h"
#include "voca/core/error.h"

namespace voca::encode {

const char* encoderKindName(EncoderKind kind) {
  switch (kind) {
    case EncoderKind::kAuto:
      return "auto";
    case EncoderKind::kX264:
      return "x264";
    case EncoderKind::kV4l2m2m:
      return "v4l2m2m";
    case EncoderKind::kVaapi:
      return "vaapi";
  }
  return "?";
}

EncoderKind parseEncoderKind(std::string_view text) {
  for (EncoderKind kind : {EncoderKind::kAuto, EncoderKind::kX264, EncoderKind::kV4l2m2m, EncoderKind::kVaapi}) {
    if (text == encoderKindName(kind)) return kind;
  }
  throw InputError(fmt::format("encoder '{}': expected auto, x264, v4l2m2m or vaapi", text));
}

const char* encoderCodecName(EncoderKind kind) {
  switch (kind) {
    case EncoderKind::kV4l2m2m:
      return "h264_v4l2m2m";
    case EncoderKind::kVaapi:
      return "h264_vaapi";
    default:
      return "libx264";
  }
}

std::string lowLatencyX264Params(int gop) {
  return fmt::format(
      "bframes=0:ref=1:keyint={}:min-keyint={}:scenecut=0:rc-lookahead=0:sync-lookahead=0:mbtree=0:force-cfr=1", gop,
      gop);
}

EncoderSettings lowLatencySettings(EncoderKind kind, const LiveEncoderSettings& live) {
  if (live.gop < 1) throw InputError(fmt::format("GOP {}: expected at least one frame between keyframes", live.gop));
  EncoderSettings settings;
  settings.codec = encoderCodecName(kind);
  settings.bitrate_bps = live.bitrate_bps;
  settings.fps_num = live.fps_num;
  settings.fps_den = live.fps_den;
  settings.two_pass = false;
  settings.constant_bitrate = true;
  settings.gop_size = live.gop;
  settings.vaapi_device = live.vaapi_device;
  // veryfast keeps a Cortex-A76 core real-time at 752x480 x2; the motion search (hex, subme 2)
  // still finds the vectors the frontend uses as priors.
  settings.x264_preset = "veryfast";
  settings.x264_tune.clear();
  settings.x264_params = lowLatencyX264Params(live.gop);
  settings.threads = 1;  // no frame threads: they would hold frames back
  settings.global_header = live.global_header;
  settings.monochrome = live.monochrome;
  return settings;
}

void setFrameRate(LiveEncoderSettings& live, double fps_hz) {
  if (!(fps_hz > 0.0) || fps_hz > 1000.0) {
    throw InputError(fmt::format("frame rate {} fps: expected 0 < fps <= 1000", fps_hz));
  }
  const long millihertz = std::lround(fps_hz * 1000.0);
  if (millihertz % 1000 == 0) {
    live.fps_num = static_cast<int>(millihertz / 1000);
    live.fps_den = 1;
  } else {
    live.fps_num = static_cast<int>(millihertz);
    live.fps_den = 1000;
  }
}

EncoderProbe systemEncoderProbe() {
  EncoderProbe probe;
  probe.v4l2m2m_present = [] {
    return avcodec_find_encoder_by_name("h264_v4l2m2m") != nullptr &&
           !platform::findM2mCodecNodes(platform::M2mRole::kEncoder, platform::fourcc("H264")).empty();
  };
  probe.vaapi_present = [](const std::string& device) {
    std::error_code ec;
    return avcodec_find_encoder_by_name("h264_vaapi") != nullptr && std::filesystem::exists(device, ec);
  };
  return probe;
}

EncoderChoice selectEncoder(const LiveEncoderSettings& live, const EncoderProbe& probe, const EncoderOpener& open) {
  EncoderChoice choice;
  const bool automatic = live.kind == EncoderKind::kAuto;
  const auto describe = [&](EncoderKind kind) {
    choice.kind = kind;
    choice.description =
        fmt::format("encoder: {} ({}, {} kbit/s, GOP {}{})", encoderKindName(kind), encoderCodecName(kind),
                    live.bitrate_bps / 1000, live.gop, live.monochrome ? ", gray 4:0:0" : "");
    return choice;
  };
  const auto attempt = [&](EncoderKind kind, bool present, const std::string& missing) -> bool {
    if (!automatic && live.kind != kind) return false;
    std::string why = missing;
    if (present) {
      try {
        open(kind);
        return true;
      } catch (const std::runtime_error& e) {
        why = e.what();
      }
    }
    choice.notes.push_back(fmt::format("{}: {}", encoderKindName(kind), why));
    if (!automatic) {
      throw InputError(
          fmt::format("encoder {} requested but unusable: {}; use --encoder x264 or auto", encoderKindName(kind), why));
    }
    return false;
  };
  // Hardware encoders code 4:2:0 only: asked for luma alone, they are not tried.
  const std::string chroma_only = "codes 4:2:0 only, and luma alone (gray, 4:0:0) was asked for";
  const bool m2m = !live.monochrome && probe.v4l2m2m_present && probe.v4l2m2m_present();
  if (attempt(EncoderKind::kV4l2m2m, m2m,
              live.monochrome ? chroma_only : "no V4L2 memory-to-memory H.264 encoder node")) {
    return describe(EncoderKind::kV4l2m2m);
  }
  const bool vaapi = !live.monochrome && probe.vaapi_present && probe.vaapi_present(live.vaapi_device);
  if (attempt(EncoderKind::kVaapi, vaapi,
              live.monochrome ? chroma_only : "no VAAPI render node " + live.vaapi_device)) {
    return describe(EncoderKind::kVaapi);
  }
  // libx264 is part of the build; it can still fail to open (bad settings), which is an error.
  if (automatic || live.kind == EncoderKind::kX264) {
    open(EncoderKind::kX264);
    return describe(EncoderKind::kX264);
  }
  throw InputError(fmt::format("encoder {}: no encoder selected", encoderKindName(live.kind)));
}

EncoderChoice openLiveEncoder(VideoEncoder& encoder, const LiveEncoderSettings& live, int width, int height) {
  return selectEncoder(live, systemEncoderProbe(),
                       [&](EncoderKind kind) { encoder.open(lowLatencySettings(kind, live), width, height); });
}

}  // namespace voca::encode
