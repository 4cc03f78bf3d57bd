// Decoder known answers: synthetic textures moving by a known sub-pixel translation / rotation,
// encoded with our encoder (libx264 with the paper's settings, MPEG-4 Part 2, MPEG-2) and decoded
// back: the motion field must match the true motion, I-frames carry none, timestamps round-trip.
// Also the backend selection with an injected device probe.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "drivers/decode/decoder_kind.h"
#include "drivers/decode/video_reader.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "test_support.h"
#include "voca/core/error.h"

namespace {

using voca::GrayImage;
using voca::decode::DecodedFrame;

// A band-limited random texture: a sum of plane waves with random directions and wavelengths of
// 6-40 px. It is defined everywhere, so a moved copy is sampled exactly (no resampling error), and
// it has no dominant period that would let the encoder match a wrong but similar block.
class WaveTexture {
 public:
  explicit WaveTexture(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI), wavelength(6.0, 40.0), phase(0.0, 2.0 * M_PI);
    for (Wave& w : waves_) {
      const double a = angle(rng), k = 2.0 * M_PI / wavelength(rng);
      w = {k * std::cos(a), k * std::sin(a), phase(rng)};
    }
  }
  std::uint8_t operator()(double x, double y) const {
    double sum = 0.0;
    for (const Wave& w : waves_) sum += std::sin(w.kx * x + w.ky * y + w.phase);
    return static_cast<std::uint8_t>(std::clamp(128.0 + 110.0 * sum / std::sqrt(double(kWaves)) * 0.9, 0.0, 255.0));
  }

 private:
  static constexpr int kWaves = 24;
  struct Wave {
    double kx, ky, phase;
  };
  Wave waves_[kWaves];
};

constexpr int kWidth = 256, kHeight = 192, kFrames = 8;

// Maps a point of frame k back to texture coordinates (where its content is in the texture).
using Motion = std::function<Eigen::Vector2d(const Eigen::Vector2d& p, int k)>;

std::vector<GrayImage> render(const WaveTexture& texture, const Motion& to_texture) {
  std::vector<GrayImage> frames;
  for (int k = 0; k < kFrames; ++k) {
    GrayImage image(kWidth, kHeight);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        const Eigen::Vector2d t = to_texture(Eigen::Vector2d(x, y), k);
        image(x, y) = texture(t.x(), t.y());
      }
    frames.push_back(std::move(image));
  }
  return frames;
}

void encode(const std::filesystem::path& path, const std::vector<GrayImage>& frames, const std::string& codec,
            bool two_pass = true, std::int64_t bitrate_bps = 2000000, const std::string& extra_x264_params = "",
            bool monochrome = false) {
  voca::encode::EncoderSettings settings;
  settings.monochrome = monochrome;
  settings.two_pass = two_pass;
  settings.x264_params += extra_x264_params;
  settings.codec = codec;              // libx264 keeps the paper's x264 parameters (quarter-pel, no B-frames)
  settings.bitrate_bps = bitrate_bps;  // default ~1 bit/pixel/frame: rate control does not starve vectors
  voca::encode::encodeVideoFile(path, settings, [&](const std::function<void(voca::GrayView)>& emit) {
    for (const GrayImage& f : frames) emit(f.view());
  });
}

std::vector<DecodedFrame> decodeAll(const std::filesystem::path& path, std::vector<std::int64_t> t_ns = {},
                                    bool skip_loop_filter = false, bool export_qp = true, bool luma_only = true) {
  voca::decode::DecoderOptions options;
  options.kind = voca::decode::DecoderKind::kSoftware;
  options.skip_loop_filter = skip_loop_filter;
  options.luma_only = luma_only;
  options.export_qp = export_qp;
  voca::decode::VideoReader reader(path, std::move(t_ns), options);
  std::vector<DecodedFrame> frames;
  DecodedFrame frame;
  while (reader.next(frame)) frames.push_back(frame);
  return frames;
}

double blockStdDev(const GrayImage& image, const voca::MotionBlock& b) {
  double sum = 0, sum2 = 0;
  for (int y = b.y; y < b.y + b.h; ++y)
    for (int x = b.x; x < b.x + b.w; ++x) {
      sum += image(x, y);
      sum2 += double(image(x, y)) * image(x, y);
    }
  const double n = double(b.w) * b.h;
  return std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
}

// Mean absolute difference of two images of the same size, in grey levels.
double meanAbsoluteError(const GrayImage& a, const GrayImage& b) {
  double sum = 0;
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x) sum += std::abs(int(a(x, y)) - int(b(x, y)));
  return sum / (double(a.width()) * a.height());
}

struct Agreement {
  int blocks = 0, within = 0;
  double fraction() const { return blocks == 0 ? 0.0 : double(within) / blocks; }
};

// Compares each textured interior block's displacement with the true forward flow at its centre.
Agreement compare(const std::vector<DecodedFrame>& frames, const Motion& to_texture, double tolerance_px) {
  Agreement a;
  for (std::size_t k = 1; k < frames.size(); ++k) {
    const DecodedFrame& f = frames[k];
    for (const voca::MotionBlock& b : f.motion.blocks()) {
      // Blocks near the border see content entering the picture: no true match exists there.
      if (b.x < 16 || b.y < 16 || b.x + b.w > kWidth - 16 || b.y + b.h > kHeight - 16) continue;
      if (blockStdDev(f.luma, b) < 10.0) continue;
      const Eigen::Vector2d c(b.centreX(), b.centreY());  // pixel-centre coordinates, like the renderer
      // The content at c came from the point of frame k-1 that shows the same texture point.
      const Eigen::Vector2d t = to_texture(c, int(k));
      // Invert frame k-1's mapping numerically (Newton on a smooth map, converges in a few steps).
      Eigen::Vector2d p = c;
      for (int it = 0; it < 20; ++it) {
        const Eigen::Vector2d r = to_texture(p, int(k) - 1) - t;
        const double h = 1e-4;
        Eigen::Matrix2d J;
        J.col(0) = (to_texture(p + Eigen::Vector2d(h, 0), int(k) - 1) - to_texture(p, int(k) - 1)) / h;
        J.col(1) = (to_texture(p + Eigen::Vector2d(0, h), int(k) - 1) - to_texture(p, int(k) - 1)) / h;
        p -= J.inverse() * r;
      }
      const Eigen::Vector2d truth = c - p;  // forward flow: frame k-1 position -> frame k position
      ++a.blocks;
      a.within += (Eigen::Vector2d(b.dx, b.dy) - truth).norm() <= tolerance_px ? 1 : 0;
    }
  }
  return a;
}

}  // namespace

TEST_CASE("H.264 vectors of a sub-pixel translation match the true motion") {
  voca::test::ScratchDir dir("decode-translation");
  const WaveTexture texture(11);
  // 1.25 px right, 0.5 px up per frame: quarter-pel exact, so the codec can represent it.
  const Motion motion = [](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(p.x() - 1.25 * k, p.y() + 0.5 * k);
  };
  encode(dir / "t.mp4", render(texture, motion), "libx264");
  std::vector<std::int64_t> t_ns;
  for (int k = 0; k < kFrames; ++k) t_ns.push_back(1403715273262142976LL + 50000000LL * k + (k % 3) * 7);
  const std::vector<DecodedFrame> frames = decodeAll(dir / "t.mp4", t_ns);
  REQUIRE(frames.size() == std::size_t(kFrames));

  CHECK(frames[0].motion.pictureType() == voca::PictureType::kI);
  CHECK_FALSE(frames[0].motion.hasVectors());
  CHECK(frames[0].motion.blockAt(kWidth / 2, kHeight / 2) == nullptr);
  for (int k = 0; k < kFrames; ++k) {
    CHECK(frames[k].t_ns == t_ns[k]);  // exact round trip of the csv timestamps
    CHECK(frames[k].frame_index == k);
    CHECK(frames[k].luma.width() == kWidth);
    if (k > 0) {
      CHECK(frames[k].motion.pictureType() == voca::PictureType::kP);
      CHECK(frames[k].motion.hasVectors());
    }
  }
  // Quarter-pel vectors: a correct vector is within one quarter-pel step of the truth; the encoder
  // may pick a neighbour when the rate-distortion trade-off favours it, hence 90 % not 100 %.
  const Agreement a = compare(frames, motion, 0.25);
  MESSAGE("translation: " << a.within << "/" << a.blocks << " blocks within 0.25 px");
  CHECK(a.blocks > 200);
  CHECK(a.fraction() >= 0.90);
  // The decoded luma is the image we encoded up to compression loss.
  const std::vector<GrayImage> truth = render(texture, motion);
  CHECK(meanAbsoluteError(truth[3], frames[3].luma) < 6.0);  // at 2 Mbit/s a few grey levels
}

TEST_CASE("a 4:0:0 (gray) H.264 stream decodes to the same kind of frames and vectors as a 4:2:0 one") {
  voca::test::ScratchDir dir("decode-monochrome");
  const WaveTexture texture(13);
  const Motion motion = [](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(p.x() - 0.75 * k, p.y() + 1.25 * k);
  };
  const std::vector<GrayImage> truth = render(texture, motion);
  encode(dir / "yuv420p.mp4", truth, "libx264");
  encode(dir / "gray.mp4", truth, "libx264", true, 2000000, "", /*monochrome=*/true);
  const std::vector<DecodedFrame> yuv420p = decodeAll(dir / "yuv420p.mp4");
  const std::vector<DecodedFrame> gray = decodeAll(dir / "gray.mp4");
  REQUIRE(gray.size() == std::size_t(kFrames));
  REQUIRE(yuv420p.size() == gray.size());
  CHECK(gray[0].motion.pictureType() == voca::PictureType::kI);
  for (int k = 1; k < kFrames; ++k) {
    CHECK(gray[k].motion.pictureType() == voca::PictureType::kP);
    CHECK(gray[k].motion.hasVectors());
  }
  // Without chroma the encoder searches and codes the same luma: its vectors follow the true
  // motion as closely as those of the 4:2:0 stream, and the pictures are as close to the input.
  const Agreement a_gray = compare(gray, motion, 0.25), a_yuv = compare(yuv420p, motion, 0.25);
  MESSAGE("4:0:0 " << a_gray.within << "/" << a_gray.blocks << ", 4:2:0 " << a_yuv.within << "/" << a_yuv.blocks
                   << " blocks within 0.25 px");
  CHECK(a_gray.blocks > 200);
  CHECK(a_gray.fraction() >= 0.90);
  CHECK(a_gray.fraction() >= a_yuv.fraction() - 0.03);
  for (int k : {0, 3, kFrames - 1}) {
    const double err_gray = meanAbsoluteError(truth[k], gray[k].luma);
    CHECK(err_gray < 6.0);
    CHECK(err_gray < 1.3 * meanAbsoluteError(truth[k], yuv420p[k].luma));
  }
}

TEST_CASE("skipping the deblocking filter keeps the vectors exact and changes only the pictures' filtering") {
  voca::test::ScratchDir dir("decode-skip-deblock");
  const WaveTexture texture(5);
  const Motion motion = [](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(p.x() - 0.75 * k, p.y() - 0.25 * k);
  };
  const std::vector<GrayImage> truth = render(texture, motion);
  // A low rate (coarse quantisation, visible block edges) so that the deblocking filter has work to do.
  encode(dir / "d.mp4", truth, "libx264", true, 150000);
  const std::vector<DecodedFrame> filtered = decodeAll(dir / "d.mp4");
  const std::vector<DecodedFrame> unfiltered = decodeAll(dir / "d.mp4", {}, true);
  REQUIRE(filtered.size() == std::size_t(kFrames));
  REQUIRE(unfiltered.size() == filtered.size());
  int differing_pixels = 0;
  for (int k = 0; k < kFrames; ++k) {
    const auto a = filtered[k].motion.blocks(), b = unfiltered[k].motion.blocks();
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      CHECK((a[i].x == b[i].x && a[i].y == b[i].y && a[i].w == b[i].w && a[i].h == b[i].h && a[i].dx == b[i].dx &&
             a[i].dy == b[i].dy));
    }
    double err_filtered = 0, err_unfiltered = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        differing_pixels += filtered[k].luma(x, y) != unfiltered[k].luma(x, y) ? 1 : 0;
        err_filtered += std::abs(int(truth[k](x, y)) - int(filtered[k].luma(x, y)));
        err_unfiltered += std::abs(int(truth[k](x, y)) - int(unfiltered[k].luma(x, y)));
      }
    // Without the filter the picture is still the encoded one up to compression loss, only not the
    // encoder's reconstruction: its error stays close to the filtered decode's.
    CHECK(err_unfiltered < 1.5 * err_filtered + 0.5 * kWidth * kHeight);
  }
  // The option is real: the filter changed pixels that the unfiltered decode leaves as they were.
  MESSAGE("skip-deblock: " << differing_pixels << " pixels differ over " << kFrames << " frames");
  CHECK(differing_pixels > 0);
}

TEST_CASE("luma-only decoding gives the luma planes and vectors of a decode with chroma") {
  voca::test::ScratchDir dir("decode-luma-only");
  const WaveTexture texture(9);
  const Motion motion = [](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(p.x() - 1.25 * k, p.y() + 0.5 * k);
  };
  const std::vector<GrayImage> truth = render(texture, motion);
  // The skipped chroma planes must not reach the luma: H.264 (with its deblocking filter, at a rate
  // low enough for the filter to act) and MPEG-2, whose decoders both honour the flag.
  for (const std::string codec : {"libx264", "mpeg2video"}) {
    CAPTURE(codec);
    const std::filesystem::path path = dir / (codec + ".mp4");
    encode(path, truth, codec, /*two_pass=*/false, 200000);
    const std::vector<DecodedFrame> with_chroma = decodeAll(path, {}, false, false, /*luma_only=*/false);
    const std::vector<DecodedFrame> luma_only = decodeAll(path, {}, false, false, /*luma_only=*/true);
    REQUIRE(with_chroma.size() == luma_only.size());
    REQUIRE(with_chroma.size() >= std::size_t(kFrames - 1));
    for (std::size_t k = 0; k < with_chroma.size(); ++k) {
      CAPTURE(k);
      REQUIRE(luma_only[k].luma.width() == kWidth);
      REQUIRE(luma_only[k].luma.height() == kHeight);
      int differing = 0;
      for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) differing += with_chroma[k].luma(x, y) != luma_only[k].luma(x, y) ? 1 : 0;
      CHECK(differing == 0);
      const auto a = with_chroma[k].motion.blocks(), b = luma_only[k].motion.blocks();
      REQUIRE(a.size() == b.size());
      for (std::size_t i = 0; i < a.size(); ++i) CHECK((a[i].dx == b[i].dx && a[i].dy == b[i].dy));
    }
  }
  const char* what = voca::decode::lumaOnlyDecodingAvailable()
                         ? "this libavcodec skips the chroma planes: a luma-only decode was compared with a full one"
                         : "this libavcodec has no luma-only decoding (built without --enable-gray): both decodes "
                           "decoded chroma; tools/build-ffmpeg.sh builds one that has it";
  MESSAGE(std::string(what));
}

TEST_CASE("H.264 macroblock quantisers: exported per block and per position, as the encoder chose them") {
  voca::test::ScratchDir dir("decode-qp");
  const WaveTexture texture(7);
  const Motion motion = [](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(p.x() - 1.5 * k, p.y() - 0.75 * k);
  };
  const std::vector<GrayImage> images = render(texture, motion);

  SUBCASE("constant QP: every P-frame block and position carries exactly the encoder's QP") {
    for (const int qp : {20, 40}) {
      CAPTURE(qp);
      // x264 constant-quantiser mode: P-frames at qp, no adaptive quantisation; I-frames a few lower (ipratio).
      encode(dir / "q.mp4", images, "libx264", false, 2000000, ":qp=" + std::to_string(qp));
      const std::vector<DecodedFrame> frames = decodeAll(dir / "q.mp4");
      REQUIRE(frames.size() == std::size_t(kFrames));
      // The I-frame has no vectors but its quantisers, below the P-frames'.
      REQUIRE(frames[0].motion.hasQp());
      const int intra_qp = frames[0].motion.qpAt(kWidth / 2, kHeight / 2);
      CHECK(intra_qp >= qp - 6);
      CHECK(intra_qp < qp);
      for (int k = 1; k < kFrames; ++k) {
        CAPTURE(k);
        const voca::MotionField& field = frames[k].motion;
        REQUIRE(field.hasVectors());
        REQUIRE(field.hasQp());
        int wrong_blocks = 0, wrong_pixels = 0;
        for (const voca::MotionBlock& b : field.blocks()) wrong_blocks += b.qp != qp;
        // Every pixel, the right and bottom edges included (192 and 256 are whole macroblocks).
        for (int y = 0; y < kHeight; ++y)
          for (int x = 0; x < kWidth; ++x) wrong_pixels += field.qpAt(x, y) != qp;
        CHECK(wrong_blocks == 0);
        CHECK(wrong_pixels == 0);
        CHECK(field.qpAt(-1, 0) == voca::MotionField::kNoQp);
        CHECK(field.qpAt(kWidth, 0) == voca::MotionField::kNoQp);
      }
      // Not asked for, not exported: the same vectors and no quantisers.
      const std::vector<DecodedFrame> without = decodeAll(dir / "q.mp4", {}, false, false);
      REQUIRE(without.size() == frames.size());
      for (std::size_t k = 1; k < without.size(); ++k) {
        CHECK_FALSE(without[k].motion.hasQp());
        CHECK(without[k].motion.qpAt(kWidth / 2, kHeight / 2) == voca::MotionField::kNoQp);
        CHECK(without[k].motion.blocks().size() == frames[k].motion.blocks().size());
      }
    }
  }
  SUBCASE("rate control: QPs stay in H.264's 0..51 and are higher at a low bitrate than at a high one") {
    double mean_qp[2] = {0, 0};
    const std::int64_t rates[2] = {100000, 4000000};
    for (int r = 0; r < 2; ++r) {
      CAPTURE(rates[r]);
      encode(dir / "r.mp4", images, "libx264", false, rates[r]);
      const std::vector<DecodedFrame> frames = decodeAll(dir / "r.mp4");
      REQUIRE(frames.size() == std::size_t(kFrames));
      int blocks = 0, out_of_range = 0;
      double sum = 0;
      for (int k = 1; k < kFrames; ++k) {
        for (const voca::MotionBlock& b : frames[k].motion.blocks()) {
          out_of_range += b.qp < 0 || b.qp > 51;
          sum += b.qp;
          ++blocks;
        }
      }
      REQUIRE(blocks > 200);
      CHECK(out_of_range == 0);
      mean_qp[r] = sum / blocks;
    }
    MESSAGE("mean P-frame block QP: " << mean_qp[0] << " at 100 kbit/s, " << mean_qp[1] << " at 4 Mbit/s");
    CHECK(mean_qp[0] > mean_qp[1] + 5.0);
  }
}

TEST_CASE("H.264 vectors of a small rotation match the true motion") {
  voca::test::ScratchDir dir("decode-rotation");
  const WaveTexture texture(23);
  // 0.4 degrees per frame about the image centre: up to ~0.9 px at the corners, varying over the
  // image, so a constant vector cannot pass.
  const double theta = 0.4 * M_PI / 180.0;
  const Eigen::Vector2d centre(kWidth / 2.0, kHeight / 2.0);
  const Motion motion = [&](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(Eigen::Rotation2Dd(-theta * k) * (p - centre) + centre);
  };
  encode(dir / "r.mp4", render(texture, motion), "libx264");
  const std::vector<DecodedFrame> frames = decodeAll(dir / "r.mp4");
  REQUIRE(frames.size() == std::size_t(kFrames));
  // A 16x16 block rotating by 0.4 degrees differs from a translation by at most 0.08 px at its corners,
  // so the block-centre flow is still representable within a quarter-pel step.
  const Agreement a = compare(frames, motion, 0.25);
  MESSAGE("rotation: " << a.within << "/" << a.blocks << " blocks within 0.25 px");
  CHECK(a.blocks > 200);
  CHECK(a.fraction() >= 0.90);
}

TEST_CASE("MPEG-4 Part 2 and MPEG-2 streams give motion vectors through the same interface") {
  voca::test::ScratchDir dir("decode-mpeg");
  const WaveTexture texture(5);
  const Motion motion = [](const Eigen::Vector2d& p, int k) {
    return Eigen::Vector2d(p.x() - 1.5 * k, p.y() - 1.0 * k);
  };
  const std::vector<GrayImage> images = render(texture, motion);
  for (const std::string codec : {"mpeg4", "mpeg2video"}) {
    CAPTURE(codec);
    encode(dir / (codec + ".mp4"), images, codec, /*two_pass=*/false);  // one pass keeps the unit test fast
    const std::vector<DecodedFrame> frames = decodeAll(dir / (codec + ".mp4"));
    REQUIRE(frames.size() == std::size_t(kFrames));
    CHECK(frames[0].motion.pictureType() == voca::PictureType::kI);
    CHECK_FALSE(frames[0].motion.hasVectors());
    // libavcodec's MPEG-2 decoder holds one frame back unless the stream is flagged low-delay and
    // returns the held frame at end of stream without side data, so its last frame has no vectors.
    const int last_with_vectors = codec == "mpeg2video" ? kFrames - 2 : kFrames - 1;
    for (int k = 1; k <= last_with_vectors; ++k) {
      CAPTURE(k);
      CHECK(frames[k].motion.pictureType() == voca::PictureType::kP);
      CHECK(frames[k].motion.hasVectors());
      // The MPEG-2-style quantiser scale (1..31 with the linear scale) comes along too.
      REQUIRE(frames[k].motion.hasQp());
      for (const voca::MotionBlock& b : frames[k].motion.blocks()) CHECK((b.qp >= 1 && b.qp <= 112));
    }
    // These codecs use half-pel vectors (1.5, 1.0 is representable), so the tolerance is one half-pel step.
    const Agreement a = compare(frames, motion, 0.5);
    MESSAGE(codec << ": " << a.within << "/" << a.blocks << " blocks within 0.5 px");
    CHECK(a.fraction() >= 0.90);
  }
}

namespace {

struct FakeMachine {
  bool render_node = false, vaapi_opens = false, v4l2 = false;
  mutable int calls = 0;
  voca::decode::DecoderProbe probe() const {
    voca::decode::DecoderProbe p;
    p.vaapi_device_present = [this](const std::string&) {
      ++calls;
      return render_node;
    };
    p.vaapi_open = [this](const std::string&, voca::decode::VideoCodec) {
      ++calls;
      return vaapi_opens;
    };
    p.v4l2m2m_present = [this](voca::decode::VideoCodec) {
      ++calls;
      return v4l2;
    };
    return p;
  }
};

}  // namespace

TEST_CASE("backend selection follows the device probe and falls back to software") {
  using voca::decode::DecoderKind;
  using voca::decode::selectDecoderKind;
  using voca::decode::VideoCodec;
  const std::string node = "/dev/dri/renderD128";

  SUBCASE("vaapi available") {
    const FakeMachine m{true, true, true};
    const auto choice = selectDecoderKind(DecoderKind::kAuto, VideoCodec::kH264, node, true, m.probe());
    CHECK(choice.kind == DecoderKind::kVaapi);
    CHECK(choice.description == "decoder: vaapi (+ software MV parse)");
  }
  SUBCASE("vaapi node present but opening fails -> next backend, then software") {
    const FakeMachine m{true, false, false};
    const auto choice = selectDecoderKind(DecoderKind::kAuto, VideoCodec::kH264, node, true, m.probe());
    CHECK(choice.kind == DecoderKind::kSoftware);
    CHECK(choice.description == "decoder: software");
    REQUIRE(choice.notes.size() == 2);
    CHECK(choice.notes[0].find("cannot open") != std::string::npos);
  }
  SUBCASE("vaapi fails, v4l2 m2m present") {
    const FakeMachine m{true, false, true};
    const auto choice = selectDecoderKind(DecoderKind::kAuto, VideoCodec::kMpeg2, node, true, m.probe());
    CHECK(choice.kind == DecoderKind::kV4l2m2m);
    CHECK(choice.description == "decoder: v4l2m2m (+ software MV parse)");
  }
  SUBCASE("nothing") {
    const FakeMachine m{};
    const auto choice = selectDecoderKind(DecoderKind::kAuto, VideoCodec::kH264, node, true, m.probe());
    CHECK(choice.kind == DecoderKind::kSoftware);
    CHECK(choice.description == "decoder: software");
  }
  SUBCASE("pixels only: no MV parse mentioned") {
    const FakeMachine m{true, true, false};
    CHECK(selectDecoderKind(DecoderKind::kAuto, VideoCodec::kH264, node, false, m.probe()).description ==
          "decoder: vaapi");
  }
  SUBCASE("software requested: no probing") {
    const FakeMachine m{true, true, true};
    CHECK(selectDecoderKind(DecoderKind::kSoftware, VideoCodec::kH264, node, true, m.probe()).kind ==
          DecoderKind::kSoftware);
    CHECK(m.calls == 0);
  }
  SUBCASE("an explicitly requested backend that is missing is an error, not a silent fallback") {
    const FakeMachine m{};
    CHECK_THROWS_AS(selectDecoderKind(DecoderKind::kVaapi, VideoCodec::kH264, node, true, m.probe()), voca::InputError);
    CHECK_THROWS_AS(selectDecoderKind(DecoderKind::kV4l2m2m, VideoCodec::kH264, node, true, m.probe()),
                    voca::InputError);
    CHECK_THROWS_AS(voca::decode::parseDecoderKind("cuda"), voca::InputError);
  }
}

TEST_CASE("a probe that promises hardware which then fails to open falls back to software and decodes") {
  voca::test::ScratchDir dir("decode-fallback");
  const WaveTexture texture(3);
  encode(dir / "f.mp4",
         render(texture, [](const Eigen::Vector2d& p, int k) { return Eigen::Vector2d(p.x() + k, p.y()); }), "libx264",
         /*two_pass=*/false);
  // Point VAAPI at a node that cannot exist and claim V4L2 M2M without a real device behind it: the
  // real open fails, and auto mode must end in software.
  FakeMachine m{true, true, false};
  const voca::decode::DecoderProbe probe = m.probe();
  voca::decode::DecoderOptions options;
  options.vaapi_device = (dir / "renderD999").string();
  voca::decode::Demuxer demuxer(dir / "f.mp4");
  voca::decode::VideoDecoder decoder(demuxer.stream(), options, &probe, "f.mp4");
  CHECK(decoder.kind() == voca::decode::DecoderKind::kSoftware);
  CHECK(decoder.description() == "decoder: software");
  voca::decode::Packet packet;
  DecodedFrame frame;
  int frames = 0, with_vectors = 0;
  while (demuxer.read(packet)) {
    decoder.send(packet);
    while (decoder.receive(frame)) {
      ++frames;
      with_vectors += frame.motion.hasVectors() ? 1 : 0;
    }
  }
  decoder.sendEnd();
  while (decoder.receive(frame)) ++frames;
  CHECK(frames == kFrames);
  CHECK(with_vectors == kFrames - 1);
}
