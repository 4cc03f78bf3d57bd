#include "drivers/decode/decoder_kind.h"

#include <filesystem>

#include "drivers/decode/ffmpeg_util.h"
#include "platform/v4l2/m2m_devices.h"
#include "voca/core/error.h"

extern "C" {
#include <libavutil/hwcontext.h>
}

namespace voca::decode {

const char* decoderKindName(DecoderKind kind) {
  switch (kind) {
    case DecoderKind::kAuto:
      return "auto";
    case DecoderKind::kSoftware:
      return "software";
    case DecoderKind::kVaapi:
      return "vaapi";
    case DecoderKind::kV4l2m2m:
      return "v4l2m2m";
  }
  return "?";
}

DecoderKind parseDecoderKind(std::string_view text) {
  for (DecoderKind b : {DecoderKind::kAuto, DecoderKind::kSoftware, DecoderKind::kVaapi, DecoderKind::kV4l2m2m}) {
    if (text == decoderKindName(b)) return b;
  }
  throw InputError("decoder '" + std::string(text) + "': expected auto, software, vaapi or v4l2m2m");
}

std::string describeDecoder(DecoderKind kind, bool export_motion) {
  std::string text = std::string("decoder: ") + decoderKindName(kind);
  if (kind != DecoderKind::kSoftware && export_motion) text += " (+ software MV parse)";
  return text;
}

DecoderChoice selectDecoderKind(DecoderKind requested, VideoCodec codec, const std::string& vaapi_device,
                                bool export_motion, const DecoderProbe& probe) {
  DecoderChoice choice;
  auto take = [&](DecoderKind kind) {
    choice.kind = kind;
    choice.description = describeDecoder(kind, export_motion);
    return choice;
  };
  if (requested == DecoderKind::kSoftware) return take(DecoderKind::kSoftware);

  if (requested == DecoderKind::kAuto || requested == DecoderKind::kVaapi) {
    if (!probe.vaapi_device_present || !probe.vaapi_device_present(vaapi_device)) {
      choice.notes.push_back("vaapi: no render node " + vaapi_device);
    } else if (!probe.vaapi_open || !probe.vaapi_open(vaapi_device, codec)) {
      choice.notes.push_back("vaapi: cannot open " + vaapi_device + " for " + videoCodecName(codec) +
                             " (driver missing or codec not supported by the GPU)");
    } else {
      return take(DecoderKind::kVaapi);
    }
    if (requested == DecoderKind::kVaapi) {
      throw InputError("decoder vaapi requested but unusable: " + choice.notes.back() +
                       "; use --decoder software or auto");
    }
  }
  if (requested == DecoderKind::kAuto || requested == DecoderKind::kV4l2m2m) {
    if (probe.v4l2m2m_present && probe.v4l2m2m_present(codec)) return take(DecoderKind::kV4l2m2m);
    choice.notes.push_back(std::string("v4l2m2m: no memory-to-memory decoder for ") + videoCodecName(codec));
    if (requested == DecoderKind::kV4l2m2m) {
      throw InputError("decoder v4l2m2m requested but unusable: " + choice.notes.back() +
                       "; use --decoder software or auto");
    }
  }
  return take(DecoderKind::kSoftware);
}

namespace detail {

const char* v4l2m2mDecoderName(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264:
      return "h264_v4l2m2m";
    case VideoCodec::kMpeg4:
      return "mpeg4_v4l2m2m";
    case VideoCodec::kMpeg2:
      return "mpeg2_v4l2m2m";
    case VideoCodec::kOther:
      break;
  }
  return nullptr;
}

AVCodecID avCodecId(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264:
      return AV_CODEC_ID_H264;
    case VideoCodec::kMpeg4:
      return AV_CODEC_ID_MPEG4;
    case VideoCodec::kMpeg2:
      return AV_CODEC_ID_MPEG2VIDEO;
    case VideoCodec::kOther:
      break;
  }
  return AV_CODEC_ID_NONE;
}

std::uint32_t v4l2Format(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kH264:
      return platform::fourcc("H264");
    case VideoCodec::kMpeg4:
      return platform::fourcc("MPG4");
    case VideoCodec::kMpeg2:
      return platform::fourcc("MPG2");
    case VideoCodec::kOther:
      break;
  }
  return 0;
}

bool codecSupportsVaapi(const AVCodec* codec) {
  for (int i = 0;; ++i) {
    const AVCodecHWConfig* config = avcodec_get_hw_config(codec, i);
    if (config == nullptr) return false;
    if ((config->methods & AV_CODEC_HW_CONFIG_METHOD_HW_DEVICE_CTX) != 0 &&
        config->device_type == AV_HWDEVICE_TYPE_VAAPI) {
      return true;
    }
  }
}

}  // namespace detail

DecoderProbe systemDecoderProbe() {
  using detail::avCodecId;
  using detail::codecSupportsVaapi;
  using detail::v4l2Format;
  using detail::v4l2m2mDecoderName;
  DecoderProbe probe;
  probe.vaapi_device_present = [](const std::string& device) {
    std::error_code ec;
    return std::filesystem::exists(device, ec);
  };
  probe.vaapi_open = [](const std::string& device, VideoCodec codec) {
    const AVCodec* decoder = avcodec_find_decoder(avCodecId(codec));
    if (decoder == nullptr || !codecSupportsVaapi(decoder)) return false;
    AVBufferRef* hw = nullptr;
    const int rc = av_hwdevice_ctx_create(&hw, AV_HWDEVICE_TYPE_VAAPI, device.c_str(), nullptr, 0);
    av_buffer_unref(&hw);
    return rc >= 0;
  };
  probe.v4l2m2m_present = [](VideoCodec codec) {
    const char* name = v4l2m2mDecoderName(codec);
    if (name == nullptr || avcodec_find_decoder_by_name(name) == nullptr) return false;
    // By capabilities, not by name: a webcam is a /dev/video* too.
    return !platform::findM2mCodecNodes(platform::M2mRole::kDecoder, v4l2Format(codec)).empty();
  };
  return probe;
}

}  // namespace voca::decode
