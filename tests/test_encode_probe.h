#pragma once
// Test helpers for the encode suites: synthetic moving frames, and an independent read-back of a
// video file with libavformat/libavcodec (what a player or our decoder would see).

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

#include "drivers/encode/video_encoder.h"
#include "voca/core/image.h"

namespace voca::test {

// Smooth value noise (several octaves of a random lattice with smoothstep blending), evaluated at
// real-valued coordinates so that a shifted frame is an exact sub-pixel translation of the scene.
class NoiseTexture {
 public:
  explicit NoiseTexture(std::uint32_t seed) {
    std::uint32_t state = seed;
    lattice_.resize(kSize * kSize);
    for (float& v : lattice_) {
      state = state * 1664525u + 1013904223u;  // LCG: the same texture on every platform
      v = static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
    }
  }
  // Intensity 0..255 at (x, y).
  float operator()(double x, double y) const {
    double sum = 0.0, weight_sum = 0.0;
    double spacing = 32.0, weight = 1.0;
    for (int octave = 0; octave < 4; ++octave, spacing /= 2.0, weight *= 0.6) {
      sum += weight * lattice(x / spacing + 17.0 * octave, y / spacing + 31.0 * octave);
      weight_sum += weight;
    }
    return static_cast<float>(255.0 * sum / weight_sum);
  }

 private:
  static constexpr int kSize = 256;
  double lattice(double u, double v) const {
    const double fu = std::floor(u), fv = std::floor(v);
    const double a = smooth(u - fu), b = smooth(v - fv);
    const int iu = static_cast<int>(fu), iv = static_cast<int>(fv);
    const auto at = [&](int i, int j) {
      return lattice_[static_cast<std::size_t>(((j % kSize) + kSize) % kSize) * kSize + ((i % kSize) + kSize) % kSize];
    };
    return (1 - b) * ((1 - a) * at(iu, iv) + a * at(iu + 1, iv)) +
           b * ((1 - a) * at(iu, iv + 1) + a * at(iu + 1, iv + 1));
  }
  static double smooth(double t) { return t * t * (3.0 - 2.0 * t); }
  std::vector<float> lattice_;
};

// A camera panning over a noise texture at (vx, vy) pixels per frame (sub-pixel steps). The
// texture is rendered once and every frame samples it bilinearly at its offset, which is an exact
// translation of the bilinear surface and cheap enough for tests under emulation.
inline std::vector<GrayImage> makePanningSequence(int width, int height, int num_frames, double vx, double vy,
                                                  std::uint32_t seed) {
  const NoiseTexture texture(seed);
  const double span_x = std::fabs(vx) * (num_frames - 1), span_y = std::fabs(vy) * (num_frames - 1);
  const int tex_w = width + static_cast<int>(std::ceil(span_x)) + 2;
  const int tex_h = height + static_cast<int>(std::ceil(span_y)) + 2;
  std::vector<float> tex(static_cast<std::size_t>(tex_w) * tex_h);
  for (int y = 0; y < tex_h; ++y)
    for (int x = 0; x < tex_w; ++x) tex[static_cast<std::size_t>(y) * tex_w + x] = texture(x, y);
  // Start where the whole path stays inside the texture, whatever the signs of vx, vy.
  const double start_x = vx < 0 ? span_x : 0.0, start_y = vy < 0 ? span_y : 0.0;
  std::vector<GrayImage> frames;
  for (int i = 0; i < num_frames; ++i) {
    const double ox = start_x + i * vx, oy = start_y + i * vy;
    const int ix = static_cast<int>(std::floor(ox)), iy = static_cast<int>(std::floor(oy));
    const float ax = static_cast<float>(ox - ix), ay = static_cast<float>(oy - iy);
    GrayImage& frame = frames.emplace_back(width, height);
    for (int y = 0; y < height; ++y) {
      const float* r0 = &tex[static_cast<std::size_t>(y + iy) * tex_w + ix];
      const float* r1 = r0 + tex_w;
      for (int x = 0; x < width; ++x) {
        const float v = (1 - ay) * ((1 - ax) * r0[x] + ax * r0[x + 1]) + ay * ((1 - ax) * r1[x] + ax * r1[x + 1]);
        frame(x, y) = static_cast<std::uint8_t>(std::lround(std::fmin(255.0f, std::fmax(0.0f, v))));
      }
    }
  }
  return frames;
}

// The default (paper) settings, pinned to one thread as the tests rely on it: x264's output is then
// deterministic, and its frame threads stall under qemu-user, where the cross-built unit tests run.
inline encode::EncoderSettings testSettings() {
  encode::EncoderSettings settings;
  settings.threads = 1;
  return settings;
}

// chroma_format_idc of an H.264 SPS NAL unit (header byte included); 1 (the default) for profiles
// that do not code it; -1 when it is not an SPS. Reads exp-Golomb fields; the SPS's first bytes
// hold no emulation-prevention bytes for the ids and profiles written here.
inline int h264SpsChromaFormatIdc(const std::uint8_t* sps, int size) {
  if (sps == nullptr || size < 5 || (sps[0] & 0x1f) != 7) return -1;
  const int profile_idc = sps[1];
  if (profile_idc != 100 && profile_idc != 110 && profile_idc != 122 && profile_idc != 244) return 1;
  int bit = 4 * 8;  // after the NAL header, profile_idc, constraint flags and level_idc
  const auto readBit = [&] {
    const int value = bit / 8 < size ? (sps[bit / 8] >> (7 - bit % 8)) & 1 : 1;
    ++bit;
    return value;
  };
  const auto readUe = [&] {
    int zeros = 0;
    while (readBit() == 0 && zeros < 16) ++zeros;
    int value = 0;
    for (int i = 0; i < zeros; ++i) value = (value << 1) | readBit();
    return (1 << zeros) - 1 + value;
  };
  readUe();         // seq_parameter_set_id
  return readUe();  // chroma_format_idc
}

// The same for the first SPS of an .mp4's avcC record.
inline int h264ChromaFormatIdc(const std::uint8_t* avcc, int size) {
  if (avcc == nullptr || size < 12 || avcc[0] != 1 || (avcc[5] & 0x1f) == 0) return -1;
  const int sps_size = (avcc[6] << 8) | avcc[7];  // after version, profile, compatibility, level, length size, count
  if (8 + sps_size > size) return -1;
  return h264SpsChromaFormatIdc(avcc + 8, sps_size);
}

// The same for the first SPS in an Annex-B byte stream (in-band headers, as a live stream has).
inline int h264AnnexBChromaFormatIdc(const std::vector<std::uint8_t>& bytes) {
  for (std::size_t i = 0; i + 3 < bytes.size(); ++i) {
    if (bytes[i] == 0 && bytes[i + 1] == 0 && bytes[i + 2] == 1 && (bytes[i + 3] & 0x1f) == 7) {
      return h264SpsChromaFormatIdc(bytes.data() + i + 3, static_cast<int>(bytes.size() - i - 3));
    }
  }
  return -1;
}

// What the file holds, as read back independently of the encoder.
struct VideoProbe {
  std::string codec_name;
  // H.264 only, from the first SPS of the .mp4's avcC record: 0 = 4:0:0 (luma alone), 1 = 4:2:0.
  // FFmpeg decodes both to yuv420p (a 4:0:0 picture gets neutral chroma), so the stream says it.
  int chroma_format_idc = -1;
  int width = 0, height = 0;
  AVRational avg_frame_rate{0, 1};
  int num_packets = 0;
  std::vector<bool> packet_keyframe;  // in file order
  std::vector<char> picture_types;    // decoded frames in output order: 'I', 'P', 'B', ...
  std::vector<GrayImage> luma;        // decoded Y planes (only if keep_luma)
  std::int64_t payload_bytes = 0;
  double duration_s = 0.0;  // stream duration from the container
};

inline VideoProbe probeVideo(const std::filesystem::path& path, bool keep_luma = false) {
  VideoProbe probe;
  AVFormatContext* format = nullptr;
  if (avformat_open_input(&format, path.c_str(), nullptr, nullptr) < 0) throw std::runtime_error("cannot open");
  avformat_find_stream_info(format, nullptr);
  const int index = av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (index < 0) throw std::runtime_error("no video stream");
  AVStream* stream = format->streams[index];
  probe.codec_name = avcodec_get_name(stream->codecpar->codec_id);
  probe.chroma_format_idc = h264ChromaFormatIdc(stream->codecpar->extradata, stream->codecpar->extradata_size);
  probe.width = stream->codecpar->width;
  probe.height = stream->codecpar->height;
  probe.avg_frame_rate = stream->avg_frame_rate;
  probe.duration_s = stream->duration * av_q2d(stream->time_base);

  const AVCodec* codec = avcodec_find_decoder(stream->codecpar->codec_id);
  AVCodecContext* ctx = avcodec_alloc_context3(codec);
  avcodec_parameters_to_context(ctx, stream->codecpar);
  ctx->thread_count = 1;
  if (avcodec_open2(ctx, codec, nullptr) < 0) throw std::runtime_error("cannot open decoder");
  AVPacket* packet = av_packet_alloc();
  AVFrame* frame = av_frame_alloc();
  const auto receive = [&] {
    while (avcodec_receive_frame(ctx, frame) == 0) {
      probe.picture_types.push_back(av_get_picture_type_char(frame->pict_type));
      if (keep_luma) {
        GrayImage& y = probe.luma.emplace_back(frame->width, frame->height);
        for (int r = 0; r < frame->height; ++r) {
          for (int c = 0; c < frame->width; ++c) y(c, r) = frame->data[0][r * frame->linesize[0] + c];
        }
      }
      av_frame_unref(frame);
    }
  };
  while (av_read_frame(format, packet) >= 0) {
    if (packet->stream_index == index) {
      ++probe.num_packets;
      probe.payload_bytes += packet->size;
      probe.packet_keyframe.push_back((packet->flags & AV_PKT_FLAG_KEY) != 0);
      avcodec_send_packet(ctx, packet);
      receive();
    }
    av_packet_unref(packet);
  }
  avcodec_send_packet(ctx, nullptr);
  receive();
  av_frame_free(&frame);
  av_packet_free(&packet);
  avcodec_free_context(&ctx);
  avformat_close_input(&format);
  return probe;
}

}  // namespace voca::test
