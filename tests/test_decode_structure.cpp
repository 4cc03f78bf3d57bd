// Streams the method cannot use correctly are refused by name: B-frames, more than one reference
// frame, interlaced coding, bit depths other than 8 and chroma other than 4:2:0 (or 4:0:0). Each
// case is a tiny clip (64x64, 8 frames) made here with libavcodec, written as an elementary
// stream and read back through the project's demuxer and decoder.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
}

#include "drivers/decode/demuxer.h"
#include "drivers/decode/video_decoder.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace fs = std::filesystem;

namespace {

constexpr int kFrames = 8;

struct ClipSpec {
  std::string codec = "libx264";
  AVPixelFormat format = AV_PIX_FMT_YUV420P;
  std::string x264_params = "bframes=0:ref=1";
  int max_b_frames = 0;     // mpeg2video / mpeg4
  bool interlaced = false;  // mpeg2video: field-based coding
  int size = 64;
};

// Writes a moving gradient, 8 frames of 64x64 (spec.size), as an elementary stream (headers in band).
void writeClip(const fs::path& path, const ClipSpec& spec) {
  const AVCodec* codec = avcodec_find_encoder_by_name(spec.codec.c_str());
  REQUIRE(codec != nullptr);
  AVCodecContext* ctx = avcodec_alloc_context3(codec);
  ctx->width = spec.size;
  ctx->height = spec.size;
  ctx->pix_fmt = spec.format;
  ctx->time_base = AVRational{1, 25};
  ctx->framerate = AVRational{25, 1};
  ctx->max_b_frames = spec.max_b_frames;
  ctx->thread_count = 1;
  if (spec.interlaced) {
    ctx->flags |= AV_CODEC_FLAG_INTERLACED_DCT | AV_CODEC_FLAG_INTERLACED_ME;
    ctx->field_order = AV_FIELD_TT;
  }
  AVDictionary* options = nullptr;
  if (spec.codec == "libx264") {
    av_dict_set(&options, "x264-params", (spec.x264_params + ":log=-1").c_str(), 0);
    av_dict_set(&options, "crf", "23", 0);
  } else {
    ctx->bit_rate = 400000;
  }
  const int opened = avcodec_open2(ctx, codec, &options);
  av_dict_free(&options);
  REQUIRE_MESSAGE(opened == 0, "cannot open " << spec.codec << " for " << av_get_pix_fmt_name(spec.format));
  AVFrame* frame = av_frame_alloc();
  frame->format = spec.format;
  frame->width = spec.size;
  frame->height = spec.size;
  REQUIRE(av_frame_get_buffer(frame, 0) == 0);
  const AVPixFmtDescriptor* desc = av_pix_fmt_desc_get(spec.format);
  const int bytes = desc->comp[0].depth > 8 ? 2 : 1;
  const int max_value = (1 << desc->comp[0].depth) - 1;
  AVPacket* packet = av_packet_alloc();
  std::ofstream out(path, std::ios::binary);
  const auto drain = [&] {
    while (avcodec_receive_packet(ctx, packet) == 0) {
      out.write(reinterpret_cast<const char*>(packet->data), packet->size);
      av_packet_unref(packet);
    }
  };
  for (int i = 0; i < kFrames; ++i) {
    REQUIRE(av_frame_make_writable(frame) == 0);
    for (int plane = 0; plane < desc->nb_components; ++plane) {
      const int w = plane == 0 ? spec.size : AV_CEIL_RSHIFT(spec.size, desc->log2_chroma_w);
      const int h = plane == 0 ? spec.size : AV_CEIL_RSHIFT(spec.size, desc->log2_chroma_h);
      for (int y = 0; y < h; ++y) {
        std::uint8_t* row = frame->data[plane] + static_cast<std::ptrdiff_t>(y) * frame->linesize[plane];
        for (int x = 0; x < w; ++x) {
          // Luma: a gradient moving 2 px per frame; chroma neutral.
          const int value =
              plane == 0 ? ((x + 2 * i) * 3 + y * 2) % (max_value / 2) + max_value / 4 : (max_value + 1) / 2;
          if (bytes == 2) {
            const auto v16 = static_cast<std::uint16_t>(value);
            std::memcpy(row + 2 * x, &v16, 2);
          } else {
            row[x] = static_cast<std::uint8_t>(value);
          }
        }
      }
    }
    frame->pts = i;
    REQUIRE(avcodec_send_frame(ctx, frame) == 0);
    drain();
  }
  REQUIRE(avcodec_send_frame(ctx, nullptr) == 0);
  drain();
  av_packet_free(&packet);
  av_frame_free(&frame);
  avcodec_free_context(&ctx);
  out.close();
  REQUIRE(out.good());
}

// Decodes the whole clip with the project's software decoder; the InputError's message, or
// "(no error)" with the number of frames when the clip is accepted.
std::string decodeClip(const fs::path& path, int* frames_out = nullptr) {
  return voca::test::inputErrorOf([&] {
    voca::decode::Demuxer demuxer(path);
    voca::decode::DecoderOptions options;
    options.kind = voca::decode::DecoderKind::kSoftware;
    options.log_choice = false;
    voca::decode::VideoDecoder decoder(demuxer.stream(), options, nullptr, path.filename().string());
    voca::decode::Packet packet;
    voca::decode::DecodedFrame frame;
    int count = 0;
    while (demuxer.read(packet)) {
      decoder.send(packet);
      while (decoder.receive(frame)) ++count;
    }
    decoder.sendEnd();
    while (decoder.receive(frame)) ++count;
    if (frames_out != nullptr) *frames_out = count;
  });
}

}  // namespace

TEST_CASE("the paper's structure decodes: 8-bit 4:2:0 and 4:0:0, no B-frames, one reference, progressive") {
  voca::test::ScratchDir dir("decode-structure-ok");
  for (const AVPixelFormat format : {AV_PIX_FMT_YUV420P, AV_PIX_FMT_GRAY8}) {
    CAPTURE(av_get_pix_fmt_name(format));
    ClipSpec spec;
    spec.format = format;
    writeClip(dir / "ok.h264", spec);
    int frames = 0;
    CHECK(decodeClip(dir / "ok.h264", &frames) == "(no error)");
    CHECK(frames == kFrames);
  }
  // MPEG-2 and MPEG-4 Part 2 without B-frames, progressive.
  for (const char* codec : {"mpeg2video", "mpeg4"}) {
    CAPTURE(codec);
    ClipSpec spec;
    spec.codec = codec;
    const fs::path file = dir / (std::string(codec) + (std::string(codec) == "mpeg4" ? ".m4v" : ".m2v"));
    writeClip(file, spec);
    int frames = 0;
    CHECK(decodeClip(file, &frames) == "(no error)");
    CHECK(frames == kFrames);
  }
}

TEST_CASE("B-frames are refused by name, in H.264 and in MPEG-4 Part 2") {
  voca::test::ScratchDir dir("decode-structure-b");
  ClipSpec h264;
  h264.x264_params = "bframes=2:ref=1:b-pyramid=none";
  writeClip(dir / "b.h264", h264);
  const std::string error = decodeClip(dir / "b.h264");
  voca::test::expectError(error, "b.h264");
  voca::test::expectError(error, "B-frames");
  voca::test::expectError(error, "bframes=0");

  ClipSpec mpeg4;
  mpeg4.codec = "mpeg4";
  mpeg4.max_b_frames = 2;
  writeClip(dir / "b.m4v", mpeg4);
  const std::string mpeg4_error = decodeClip(dir / "b.m4v");
  voca::test::expectError(mpeg4_error, "b.m4v");
  voca::test::expectError(mpeg4_error, "is a B-frame");
}

TEST_CASE("more than one reference frame is refused: the vectors do not say which past frame they use") {
  voca::test::ScratchDir dir("decode-structure-refs");
  ClipSpec spec;
  spec.x264_params = "bframes=0:ref=3";
  writeClip(dir / "refs.h264", spec);
  const std::string error = decodeClip(dir / "refs.h264");
  voca::test::expectError(error, "refs.h264: the stream uses up to 3 reference frames");
  voca::test::expectError(error, "ref=1");
}

TEST_CASE("interlaced coding is refused: H.264 MBAFF and MPEG-2 field pictures") {
  voca::test::ScratchDir dir("decode-structure-interlaced");
  ClipSpec h264;
  h264.x264_params = "bframes=0:ref=1:interlaced=1";
  writeClip(dir / "mbaff.h264", h264);
  voca::test::expectError(decodeClip(dir / "mbaff.h264"), "mbaff.h264: frame 0 is interlaced");
  ClipSpec mpeg2;
  mpeg2.codec = "mpeg2video";
  mpeg2.interlaced = true;
  writeClip(dir / "fields.m2v", mpeg2);
  voca::test::expectError(decodeClip(dir / "fields.m2v"), "fields.m2v: frame 0 is interlaced");
}

TEST_CASE("bit depths other than 8 and chroma other than 4:2:0 are refused by name") {
  voca::test::ScratchDir dir("decode-structure-format");
  const struct {
    AVPixelFormat format;
    const char* expected;
  } cases[] = {{AV_PIX_FMT_YUV420P10LE, "pixel format yuv420p10le (10-bit 4:2:0)"},
               {AV_PIX_FMT_YUV422P, "pixel format yuv422p (8-bit 4:2:2)"},
               {AV_PIX_FMT_YUV444P, "pixel format yuv444p (8-bit 4:4:4)"}};
  for (const auto& c : cases) {
    CAPTURE(c.expected);
    ClipSpec spec;
    spec.format = c.format;
    writeClip(dir / "format.h264", spec);
    const std::string error = decodeClip(dir / "format.h264");
    voca::test::expectError(error, c.expected);
    voca::test::expectError(error, "VOCA needs 8-bit 4:2:0");
  }
}

TEST_CASE("a frame size change within a raw stream is refused, not passed on to stages sized for the first") {
  voca::test::ScratchDir dir("decode-structure-resize");
  ClipSpec first, second;
  second.size = 48;
  writeClip(dir / "a.h264", first);
  writeClip(dir / "b.h264", second);
  {
    std::ofstream joined(dir / "joined.h264", std::ios::binary);
    for (const char* part : {"a.h264", "b.h264"}) {
      std::ifstream in(dir / part, std::ios::binary);
      joined << in.rdbuf();
    }
  }
  voca::test::expectError(decodeClip(dir / "joined.h264"),
                          "joined.h264: frame 8 is 48x48 but the stream starts at 64x64");
}
