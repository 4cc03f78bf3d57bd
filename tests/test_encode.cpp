// Encoder: synthetic moving sequences encoded in memory and read back with libavformat.

#include <cmath>
#include <fstream>
#include <iterator>
#include <numeric>
#include <tuple>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "tests/test_encode_probe.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::encode;

namespace {

// A texture panning by (0.37, -0.21) px per frame: sub-pixel motion in both axes, as a slowly
// moving camera gives.
std::vector<GrayImage> makeSequence(int width, int height, int num_frames) {
  return test::makePanningSequence(width, height, num_frames, 0.37, -0.21, 7);
}

FrameSource sourceOf(const std::vector<GrayImage>& frames, int* calls = nullptr) {
  return [&frames, calls](const std::function<void(GrayView)>& emit) {
    if (calls != nullptr) ++*calls;
    for (const GrayImage& frame : frames) emit(frame.view());
  };
}

std::string fileBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

double meanOf(const GrayImage& image) {
  double sum = 0.0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) sum += image(x, y);
  return sum / static_cast<double>(image.pixelCount());
}

double psnr(const GrayImage& a, const GrayImage& b, int width, int height) {
  double sse = 0.0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double d = static_cast<double>(a(x, y)) - b(x, y);
      sse += d * d;
    }
  }
  return 10.0 * std::log10(255.0 * 255.0 / (sse / (static_cast<double>(width) * height)));
}

}  // namespace

TEST_CASE("parseBitrate accepts plain numbers and k/M suffixes") {
  CHECK(parseBitrate("500k") == 500000);
  CHECK(parseBitrate("500K") == 500000);
  CHECK(parseBitrate("1M") == 1000000);
  CHECK(parseBitrate("1.5M") == 1500000);
  CHECK(parseBitrate("1000000") == 1000000);
  CHECK(parseBitrate("250000") == 250000);
}

TEST_CASE("bitrateLabel spells rates in kilobits when whole, and parseBitrate reads every label back") {
  CHECK(bitrateLabel(500000) == "500k");
  CHECK(bitrateLabel(1000000) == "1000k");
  CHECK(bitrateLabel(2000000) == "2000k");
  CHECK(bitrateLabel(1500) == "1500");
  for (const std::int64_t bps : {1000LL, 1500LL, 250000LL, 1000000LL, 1500000LL, 12345678LL}) {
    CHECK(parseBitrate(bitrateLabel(bps)) == bps);
  }
}

TEST_CASE("two-pass libx264 with the paper's settings: frames, rate, GOP and bitrate") {
  // 2 s at 30 fps. 192x144 keeps this fast under emulation; 200 kbit/s gives it about the bits per
  // pixel of the paper's 500 kbit/s at 320x240.
  const int width = 192, height = 144, num_frames = 60;
  const std::vector<GrayImage> frames = makeSequence(width, height, num_frames);
  test::ScratchDir dir("encode-x264");
  const auto path = dir / "seq.mp4";
  EncoderSettings settings = test::testSettings();  // libx264, 30 fps, paper x264 params, two-pass
  settings.bitrate_bps = 200000;
  int source_calls = 0;
  std::vector<int> frames_seen(3, 0);
  const EncodeResult result =
      encodeVideoFile(path, settings, sourceOf(frames, &source_calls), [&](int pass, int passes, int) {
        CHECK(passes == 2);
        ++frames_seen.at(pass);
      });
  CHECK(source_calls == 2);  // once per pass
  CHECK(frames_seen[1] == num_frames);
  CHECK(frames_seen[2] == num_frames);
  REQUIRE(std::filesystem::exists(path));
  CHECK(result.num_frames == num_frames);
  CHECK(result.width == width);
  CHECK(result.height == height);
  CHECK(result.num_keyframes == 1);
  CHECK(result.pass_ms_per_frame.size() == 2);
  CHECK(result.file_bytes == static_cast<std::int64_t>(std::filesystem::file_size(path)));

  const test::VideoProbe probe = test::probeVideo(path, /*keep_luma=*/true);
  CHECK(probe.codec_name == "h264");
  CHECK(probe.width == width);
  CHECK(probe.height == height);
  CHECK(av_cmp_q(probe.avg_frame_rate, AVRational{30, 1}) == 0);
  CHECK(probe.num_packets == num_frames);
  // The mp4 muxer rewrites Annex-B start codes as 4-byte lengths (3-byte codes grow by one byte).
  CHECK(probe.payload_bytes == doctest::Approx(result.payload_bytes).epsilon(0.001));
  REQUIRE(probe.picture_types.size() == static_cast<std::size_t>(num_frames));
  // keyint=1000 and no scene cut in a smooth pan: one I-frame, then P only (bframes=0: no B).
  CHECK(probe.picture_types.front() == 'I');
  CHECK(std::count(probe.picture_types.begin(), probe.picture_types.end(), 'P') == num_frames - 1);
  CHECK(probe.packet_keyframe.front());
  CHECK(std::count(probe.packet_keyframe.begin(), probe.packet_keyframe.end(), true) == 1);
  // The container duration is num_frames at 30 fps (pts = frame index).
  CHECK(probe.duration_s == doctest::Approx(num_frames / 30.0).epsilon(1e-6));

  // Two-pass ABR spends the bit budget over the whole sequence; what remains is x264's per-frame
  // quantiser rounding on a 2 s clip, which stays within a few percent. 15 % leaves room for
  // x264 versions while still catching a wrong unit (kbit vs bit), a dropped pass or CRF mode.
  CHECK(result.achieved_bitrate_bps == doctest::Approx(200000.0).epsilon(0.15));

  // Gray values go into luma unchanged (full range): the decoded mean brightness matches the
  // input within 1 level, where a studio-range squeeze (16..235) would shift it by ~4 levels on
  // this mid-gray texture, and the picture itself is close at this generous bitrate (> 30 dB).
  REQUIRE(probe.luma.size() == frames.size());
  for (std::size_t i : {std::size_t{0}, std::size_t{30}, frames.size() - 1}) {
    CHECK(std::fabs(meanOf(probe.luma[i]) - meanOf(frames[i])) < 1.0);
    CHECK(psnr(probe.luma[i], frames[i], width, height) > 30.0);
  }
}

TEST_CASE("frame rate is selectable and becomes the stream rate") {
  const std::vector<GrayImage> frames = makeSequence(160, 128, 20);
  test::ScratchDir dir("encode-fps");
  EncoderSettings settings = test::testSettings();
  settings.fps_num = 20;
  settings.two_pass = false;
  encodeVideoFile(dir / "a.mp4", settings, sourceOf(frames));
  const test::VideoProbe probe = test::probeVideo(dir / "a.mp4");
  CHECK(av_cmp_q(probe.avg_frame_rate, AVRational{20, 1}) == 0);
  CHECK(probe.duration_s == doctest::Approx(1.0).epsilon(1e-6));
}

TEST_CASE("odd frame sizes are coded whole: decoders return the original size, last column and row included") {
  // KITTI 00-02 are 1241x376. H.264 signals the size through the SPS crop window; libx264 codes an
  // odd size as 4:0:0, whose crop unit is one pixel. MPEG-4/MPEG-2 store the size as it is.
  // Plain variables, not a structured binding: CAPTURE's and the checks' lambdas cannot capture one
  // in clang before 16.
  for (const auto& size_case :
       {std::tuple{"libx264", 161, 121}, std::tuple{"libx264", 161, 120}, std::tuple{"libx264", 160, 121},
        std::tuple{"mpeg4", 161, 121}, std::tuple{"mpeg2video", 161, 121}}) {
    const char* const codec = std::get<0>(size_case);
    const int width = std::get<1>(size_case);
    const int height = std::get<2>(size_case);
    CAPTURE(codec);
    CAPTURE(width);
    CAPTURE(height);
    const std::vector<GrayImage> frames = makeSequence(width, height, 5);
    test::ScratchDir dir("encode-odd");
    EncoderSettings settings = test::testSettings();
    settings.codec = codec;
    settings.two_pass = false;
    settings.bitrate_bps = 2000000;
    const EncodeResult result = encodeVideoFile(dir / "odd.mp4", settings, sourceOf(frames));
    CHECK(result.width == width);
    CHECK(result.height == height);
    const test::VideoProbe probe = test::probeVideo(dir / "odd.mp4", true);
    if (std::string(codec) == "libx264") CHECK(probe.chroma_format_idc == 0);
    CHECK(probe.width == width);
    CHECK(probe.height == height);
    REQUIRE(probe.luma.size() == frames.size());
    CHECK(probe.luma[0].width() == width);
    CHECK(probe.luma[0].height() == height);
    // Pixel (x, y) stays at (x, y), and the odd last column and row carry the image, not padding.
    CHECK(psnr(probe.luma[0], frames[0], width, height) > 30.0);
    const auto lastColumnError = [&](const GrayImage& decoded, const GrayImage& input) {
      double sum = 0.0;
      for (int y = 0; y < height; ++y)
        sum += std::abs(static_cast<double>(decoded(width - 1, y)) - input(width - 1, y));
      return sum / height;
    };
    CHECK(lastColumnError(probe.luma[0], frames[0]) < 8.0);
  }
}

TEST_CASE("monochrome: libx264 stores luma alone (4:0:0) where the default stores 4:2:0; other codecs refuse") {
  const int width = 160, height = 128;
  const std::vector<GrayImage> frames = makeSequence(width, height, 10);
  test::ScratchDir dir("encode-monochrome");
  EncoderSettings settings = test::testSettings();
  settings.two_pass = false;
  settings.bitrate_bps = 1000000;
  encodeVideoFile(dir / "yuv420p.mp4", settings, sourceOf(frames));
  settings.monochrome = true;
  encodeVideoFile(dir / "gray.mp4", settings, sourceOf(frames));
  const test::VideoProbe yuv420p = test::probeVideo(dir / "yuv420p.mp4", true);
  const test::VideoProbe gray = test::probeVideo(dir / "gray.mp4", true);
  CHECK(yuv420p.chroma_format_idc == 1);
  CHECK(gray.chroma_format_idc == 0);
  REQUIRE(gray.luma.size() == frames.size());
  for (std::size_t i : {std::size_t{0}, frames.size() - 1}) {
    CHECK(psnr(gray.luma[i], frames[i], width, height) > 30.0);
    CHECK(std::fabs(meanOf(gray.luma[i]) - meanOf(frames[i])) < 1.0);  // full range, as 4:2:0
  }
  for (const char* codec : {"mpeg4", "mpeg2video"}) {
    CAPTURE(codec);
    settings.codec = codec;
    CHECK_THROWS_AS(encodeVideoFile(dir / "refused.mp4", settings, sourceOf(frames)), InputError);
  }
}

TEST_CASE("mpeg4 and mpeg2video go through the same function and honour the bitrate") {
  const int width = 192, height = 144, num_frames = 60;
  const std::vector<GrayImage> frames = makeSequence(width, height, num_frames);
  for (const char* codec : {"mpeg4", "mpeg2video"}) {
    for (bool two_pass : {false, true}) {
      CAPTURE(codec);
      CAPTURE(two_pass);
      test::ScratchDir dir("encode-mpeg");
      EncoderSettings settings = test::testSettings();
      settings.codec = codec;
      settings.two_pass = two_pass;
      settings.bitrate_bps = 150000;
      const EncodeResult result = encodeVideoFile(dir / "v.mp4", settings, sourceOf(frames));
      const test::VideoProbe probe = test::probeVideo(dir / "v.mp4");
      CHECK(probe.codec_name == codec);
      CHECK(probe.width == width);
      CHECK(probe.height == height);
      CHECK(av_cmp_q(probe.avg_frame_rate, AVRational{30, 1}) == 0);
      CHECK(probe.picture_types.size() == static_cast<std::size_t>(num_frames));
      CHECK(probe.picture_types.front() == 'I');
      CHECK(std::count(probe.picture_types.begin(), probe.picture_types.end(), 'B') == 0);
      MESSAGE(std::string(codec) << (two_pass ? " two-pass: " : " one-pass: ") << result.achieved_bitrate_bps
                                 << " bit/s");
      if (two_pass) {
        // MPEG quantisers are whole numbers 2..31 and one I-frame takes a large share of a 2 s
        // clip, so libavcodec's two-pass control lands coarser than x264: measured 0.71-1.11x of
        // the target over sizes 160x120-192x144 and 100-200 kbit/s. 30 % still fails for an
        // ignored bitrate (the 200k default would be +33 %, q=2 or q=31 far off).
        CHECK(result.achieved_bitrate_bps == doctest::Approx(150000.0).epsilon(0.30));
      } else {
        // One-pass MPEG rate control has no lookahead and overshoots on a 2 s clip: only the
        // order of magnitude is checked here; two-pass checks the rate.
        CHECK(result.achieved_bitrate_bps > 0.5 * 150000.0);
        CHECK(result.achieved_bitrate_bps < 2.0 * 150000.0);
      }
    }
  }
}

TEST_CASE("frame-by-frame encoder: packets in order, first keyframe, all frames out after flush") {
  const std::vector<GrayImage> frames = makeSequence(160, 128, 30);
  EncoderSettings settings = test::testSettings();
  settings.two_pass = false;
  settings.x264_tune = "zerolatency";  // the live setting: no lookahead, a packet per frame
  VideoEncoder encoder;
  encoder.open(settings, 160, 128);
  std::vector<EncodedPacket> all;
  int packets_during_encode = 0;
  for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
    const auto packets = encoder.encode(frames[i].view(), i);
    packets_during_encode += static_cast<int>(packets.size());
    all.insert(all.end(), packets.begin(), packets.end());
  }
  const auto tail = encoder.flush();
  all.insert(all.end(), tail.begin(), tail.end());
  // zerolatency has no frame delay: every frame's packet comes out of its own encode() call.
  CHECK(packets_during_encode == static_cast<int>(frames.size()));
  REQUIRE(all.size() == frames.size());
  CHECK(all.front().keyframe);
  for (std::size_t i = 0; i < all.size(); ++i) {
    CHECK(all[i].pts == static_cast<std::int64_t>(i));
    CHECK(all[i].dts == all[i].pts);  // no B-frames: decode order is capture order
    CHECK(!all[i].bytes.empty());
    if (i > 0) CHECK(!all[i].keyframe);
  }
}

TEST_CASE("encoding is reproducible within a process: the same frames give the same bytes every time") {
  // x264's AVX-512 routines read memory they never wrote, so a video encoded after another one in
  // the same process used to differ from run to run (video_encoder.cpp, withReproducibleX264Asm).
  // Each encode leaves the heap full of its own data; the next ones must not depend on it. The
  // EuRoC frame size matters: at 320x240 the old failure did not show. Measured without the fix on
  // an AVX-512 machine (40 frames): this case failed in 6 of 8 runs; with it, in none of 8.
  silenceCodecLogs();
#if defined(__x86_64__)
  const int width = 752, height = 480, num_frames = 40, repeats = 4;
#else
  // Elsewhere (ARM under qemu in CI, where x264 is slow) a smaller check of the same property.
  const int width = 320, height = 240, num_frames = 20, repeats = 2;
#endif
  const std::vector<GrayImage> frames = makeSequence(width, height, num_frames);
  const std::vector<GrayImage> other = test::makePanningSequence(width, height, num_frames, -1.3, 0.8, 3);
  test::ScratchDir dir("encode-reproducible");
  const EncoderSettings settings = test::testSettings();
  std::vector<std::string> videos;
  for (int i = 0; i < repeats; ++i) {
    encodeVideoFile(dir / "other.mp4", settings, sourceOf(other));
    encodeVideoFile(dir / "frames.mp4", settings, sourceOf(frames));
    videos.push_back(fileBytes(dir / "frames.mp4"));
  }
  for (std::size_t i = 1; i < videos.size(); ++i) CHECK(videos[i] == videos[0]);
}
