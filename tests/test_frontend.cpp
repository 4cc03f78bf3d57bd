// Frontend unit tests: pyramid, patterns, patch Jacobian and alignment, detector, and the tracker
// on synthetic textures with known motion, including the codec-prior modes.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include "tests/test_frontend_support.h"
#include "tests/test_support.h"
#include "voca/frontend/detector.h"
#include "voca/frontend/frontend.h"
#include "voca/frontend/image_shift.h"
#include "voca/frontend/patch.h"
#include "voca/frontend/pyramid.h"
#include "voca/frontend/round_trip.h"
#include "voca/frontend/temporal_tracker.h"
#include "voca/frontend/track_store.h"

using namespace voca;
using voca::test::WaveTexture;

namespace {

GrayImage renderArbitrary(int width, int height, const std::function<double(double, double)>& f) {
  GrayImage image(width, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image(x, y) = static_cast<std::uint8_t>(std::clamp(std::round(f(x, y)), 0.0, 255.0));
    }
  }
  return image;
}

// A motion field of 16x16 blocks that all carry the same forward displacement.
void uniformField(MotionField& field, int width, int height, const Eigen::Vector2f& flow, PictureType type) {
  field.reset(width, height, type);
  if (type != PictureType::kI) {
    for (int y = 0; y < height; y += 16) {
      for (int x = 0; x < width; x += 16) field.addBlock(x, y, 16, 16, flow.x(), flow.y());
    }
  }
  field.finalize();
}

}  // namespace

TEST_CASE("pyramid: binomial smoothing keeps linear ramps, so level l samples level 0 at 2^l x") {
  // A linear function is reproduced exactly by the symmetric [1 4 6 4 1]/16 kernel away from the
  // replicated border; values are exact in float up to rounding of a few ulps.
  const int w = 200, h = 120;
  GrayImage image = renderArbitrary(w, h, [](double x, double y) { return 10.0 + 0.5 * x + 0.25 * y; });
  // The ramp is rounded to 8 bits at odd coordinates; use only even pixels where it is exact.
  ImagePyramid pyramid(w, h, 4);
  pyramid.build(image.view());
  CHECK(pyramid.level(1).width == 100);
  CHECK(pyramid.level(3).width == 25);
  CHECK(pyramid.level(3).height == 15);
  for (int l = 1; l < 4; ++l) {
    const FloatView level = pyramid.level(l);
    const int s = 1 << l;
    for (int y = 4; y < level.height - 4; ++y) {
      for (int x = 4; x < level.width - 4; ++x) {
        // 8-bit rounding of the input: +-0.5 per pixel, averaged by the kernel; bound 0.5.
        CHECK(std::abs(level(x, y) - (10.0 + 0.5 * s * x + 0.25 * s * y)) <= 0.5);
      }
    }
  }
  // A constant image stays constant at every level, borders included.
  GrayImage flat(w, h, 77);
  pyramid.build(flat.view());
  for (int l = 0; l < 4; ++l) {
    const FloatView level = pyramid.level(l);
    for (int y = 0; y < level.height; ++y)
      for (int x = 0; x < level.width; ++x) REQUIRE(level(x, y) == doctest::Approx(77.f).epsilon(1e-6));
  }
}

TEST_CASE("pyramid: presmooth applies [1 2 1]/4 to level 0: ramps and constants kept, Nyquist detail removed") {
  const int w = 64, h = 48;
  ImagePyramid smooth(w, h, 3, true), plain(w, h, 3, false);
  // The smoothing is chosen per image: a pyramid that may smooth builds plain images unchanged.
  ImagePyramid may_smooth(w, h, 3, true);
  // A linear ramp passes a symmetric kernel unchanged away from the border (the replicated border
  // bends it there); 8-bit inputs at integer steps are exact.
  const GrayImage ramp = renderArbitrary(w, h, [](double x, double y) { return 20.0 + 2.0 * x + 1.0 * y; });
  smooth.build(ramp.view(), true);
  plain.build(ramp.view());
  for (int y = 1; y < h - 1; ++y)
    for (int x = 1; x < w - 1; ++x) CHECK(smooth.level(0)(x, y) == plain.level(0)(x, y));
  // Constant: unchanged everywhere, borders included.
  const GrayImage flat(w, h, 90);
  smooth.build(flat.view(), true);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) CHECK(smooth.level(0)(x, y) == 90.f);
  // A one-pixel checkerboard (the Nyquist frequency) has zero response: the mean remains.
  const GrayImage checker = renderArbitrary(
      w, h, [](double x, double y) { return (static_cast<int>(x) + static_cast<int>(y)) % 2 == 0 ? 100.0 : 200.0; });
  smooth.build(checker.view(), true);
  for (int y = 1; y < h - 1; ++y)
    for (int x = 1; x < w - 1; ++x) CHECK(smooth.level(0)(x, y) == 150.f);
  plain.build(checker.view());
  may_smooth.build(checker.view(), false);
  for (int l = 0; l < 3; ++l) {
    for (int y = 0; y < plain.level(l).height; ++y)
      for (int x = 0; x < plain.level(l).width; ++x) REQUIRE(may_smooth.level(l)(x, y) == plain.level(l)(x, y));
  }
  // Smoothing needs the scratch rows reserved at construction.
  CHECK_THROWS_AS(plain.build(checker.view(), true), std::logic_error);
  // The other levels are built from the smoothed level 0, with the same sizes.
  CHECK(smooth.level(2).width == plain.level(2).width);
  CHECK(smooth.level(2)(5, 5) == doctest::Approx(150.f));
}

TEST_CASE("patterns: 24 and 52 points, symmetric, distinct, on the 2 px grid inside 11x11 and 15x15") {
  for (const auto& [pattern, half] : {std::pair{&pattern24(), 5.f}, std::pair{&pattern52(), 7.f}}) {
    float sx = 0.f, sy = 0.f;
    for (int i = 0; i < pattern->size; ++i) {
      const float x = pattern->x[static_cast<std::size_t>(i)], y = pattern->y[static_cast<std::size_t>(i)];
      CHECK(std::abs(x) <= half);
      CHECK(std::abs(y) <= half);
      CHECK(std::fmod(std::abs(x), 2.f) == 1.f);
      sx += x;
      sy += y;
      for (int j = 0; j < i; ++j) {
        CHECK_FALSE((x == pattern->x[static_cast<std::size_t>(j)] && y == pattern->y[static_cast<std::size_t>(j)]));
      }
    }
    CHECK(sx == 0.f);
    CHECK(sy == 0.f);
  }
  CHECK(pattern24().size == 24);
  CHECK(pattern52().size == 52);
  CHECK(patternBySize(52) == &pattern52());
  CHECK(patternBySize(30) == nullptr);
}

TEST_CASE("patch: analytic Jacobian of the normalised residual matches numerical differentiation") {
  // Smooth texture (wavelengths 25..80 px): the interpolated central-difference gradient and the
  // numerical derivative of the bilinear surface then agree to O((2 pi / lambda)^2 / 4) < 2 %;
  // tolerance 3 % of each Jacobian column's norm.
  // The image is float (no 8-bit rounding, whose noise would dominate the comparison).
  const WaveTexture texture(7, 24, 25.0, 80.0, 90.0);
  FloatImage image(96, 96);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) image(x, y) = static_cast<float>(texture.at(x, y));
  const FloatView view = image.view();
  for (const PatchPattern* pattern : {&pattern24(), &pattern52()}) {
    const Eigen::Vector2f center(47.5f, 40.5f);  // cell centres: finite differences stay inside one cell
    PatchTemplate tmpl;
    PatchJacobian jac;
    tmpl.build(view, center, *pattern, &jac);
    REQUIRE(tmpl.valid);
    const int n = pattern->size;
    const auto normalised = [&](const Eigen::Vector3f& xi, std::vector<double>& out) {
      const SE2f warp = SE2f::exp(xi);
      double sum = 0.0;
      out.assign(static_cast<std::size_t>(n), 0.0);
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector2f q(pattern->x[static_cast<std::size_t>(i)], pattern->y[static_cast<std::size_t>(i)]);
        const Eigen::Vector2f p = center + warp * q;
        out[static_cast<std::size_t>(i)] = sampleBilinear(view, p.x(), p.y());
        sum += out[static_cast<std::size_t>(i)];
      }
      for (double& v : out) v *= n / sum;
    };
    std::vector<double> base, plus, minus;
    normalised(Eigen::Vector3f::Zero(), base);
    for (int i = 0; i < n; ++i)
      CHECK(tmpl.value[static_cast<std::size_t>(i)] ==
            doctest::Approx(base[static_cast<std::size_t>(i)]).epsilon(1e-5));
    const float eps[3] = {0.02f, 0.02f, 0.002f};
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3f d = Eigen::Vector3f::Zero();
      d[c] = eps[c];
      normalised(d, plus);
      normalised(-d, minus);
      double err2 = 0.0, norm2 = 0.0;
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        const double numeric = (plus[k] - minus[k]) / (2.0 * eps[c]);
        err2 += (numeric - jac[c][k]) * (numeric - jac[c][k]);
        norm2 += numeric * numeric;
      }
      INFO("pattern " << n << " column " << c);
      CHECK(norm2 > 0.0);
      CHECK(std::sqrt(err2) <= 0.03 * std::sqrt(norm2));
    }
    // step = H^-1 J^T: step * J = identity.
    Eigen::Matrix3d product = Eigen::Matrix3d::Zero();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < n; ++i)
          product(r, c) += tmpl.step[r][static_cast<std::size_t>(i)] * jac[c][static_cast<std::size_t>(i)];
    CHECK((product - Eigen::Matrix3d::Identity()).norm() < 1e-4);
  }
}

TEST_CASE("patch: coarse-to-fine alignment recovers a known shift, rotation and brightness change") {
  // Amplitude 40 keeps the texture inside 0..255 so the gain below does not clip.
  const WaveTexture texture(11, 48, 6.0, 60.0, 40.0);
  const int w = 240, h = 200;
  const double theta = 0.03;
  const Eigen::Vector2d c(120.0, 100.0), t(6.3, -4.7);
  const GrayImage a = renderArbitrary(w, h, [&](double x, double y) { return texture.at(x, y); });
  // b shows a's content rotated by theta about c, shifted by t, and 20 % darker (the mean
  // normalisation must absorb a gain).
  const GrayImage b = renderArbitrary(w, h, [&](double x, double y) {
    const Eigen::Vector2d q = Eigen::Rotation2Dd(-theta) * (Eigen::Vector2d(x, y) - c - t) + c;
    return 0.8 * texture.at(q.x(), q.y());
  });
  ImagePyramid pa(w, h, 4), pb(w, h, 4);
  pa.build(a.view());
  pb.build(b.view());
  AlignParams params;
  params.max_iterations = 10;
  int checked = 0;
  for (const Eigen::Vector2f& p :
       {Eigen::Vector2f(90.f, 80.f), Eigen::Vector2f(150.3f, 120.6f), Eigen::Vector2f(120.f, 60.f)}) {
    SE2f T(0.f, p);
    REQUIRE(trackPatch(pa, pb, p, pattern52(), params, 4, T) == AlignStatus::kConverged);
    const Eigen::Vector2d expected = Eigen::Rotation2Dd(theta) * (p.cast<double>() - c) + c + t;
    // Bilinear interpolation of 6 px wavelengths and 8-bit rounding leave ~0.03 px (measured); bound 0.05.
    CHECK((T.translation().cast<double>() - expected).norm() < 0.05);
    CHECK(std::abs(T.angle() - theta) < 0.01);
    ++checked;
  }
  CHECK(checked == 3);
  // A uniform patch has no texture: the template is rejected rather than producing a NaN.
  GrayImage flat(w, h, 100);
  ImagePyramid pf(w, h, 4);
  pf.build(flat.view());
  SE2f T(0.f, Eigen::Vector2f(100.f, 100.f));
  CHECK(trackPatch(pf, pf, Eigen::Vector2f(100.f, 100.f), pattern52(), params, 4, T) == AlignStatus::kTemplateInvalid);
  // A patch pushed mostly outside the target image is rejected.
  PatchTemplate tmpl;
  tmpl.build(pa.level(0), Eigen::Vector2f(100.f, 100.f), pattern52());
  REQUIRE(tmpl.valid);
  SE2f outside(0.f, Eigen::Vector2f(-5.f, 100.f));
  CHECK(alignPatch(pb.level(0), tmpl, pattern52(), params, outside) == AlignStatus::kTooFewPoints);
}

TEST_CASE("patch: pyramid templates built level by level equal those built at once") {
  const WaveTexture texture(7, 48, 5.0, 30.0);
  const int w = 200, h = 160;
  const GrayImage image = renderArbitrary(w, h, [&](double x, double y) { return texture.at(x, y); });
  ImagePyramid pyramid(w, h, 4);
  pyramid.build(image.view());
  const Eigen::Vector2f px(97.3f, 71.8f);
  std::array<PatchTemplate, 4> at_once, later;
  buildPyramidPatch(pyramid, px, pattern52(), at_once);
  // The finest two now (a round trip on two levels), the rest when a track needs them.
  buildPyramidPatch(pyramid, px, pattern52(), std::span<PatchTemplate>(later).first(2));
  CHECK_FALSE(later[2].valid);
  buildPyramidPatch(pyramid, px, pattern52(), later, 2);
  for (std::size_t level = 0; level < at_once.size(); ++level) {
    INFO("level " << level);
    REQUIRE(at_once[level].valid);
    CHECK(later[level].valid);
    CHECK(later[level].value == at_once[level].value);
    for (int r = 0; r < 3; ++r) CHECK(later[level].step[r] == at_once[level].step[r]);
  }
}

TEST_CASE("patch: skip_coarse_outside lets the finer levels track a patch the coarse levels lose at the border") {
  const WaveTexture texture(11, 48, 6.0, 60.0, 40.0);
  const int w = 240, h = 200;
  const Eigen::Vector2d t(-9.3, -8.6);  // towards the top-left corner
  const GrayImage a = renderArbitrary(w, h, [&](double x, double y) { return texture.at(x, y); });
  const GrayImage b = renderArbitrary(w, h, [&](double x, double y) { return texture.at(x - t.x(), y - t.y()); });
  ImagePyramid pa(w, h, 4), pb(w, h, 4);
  pa.build(a.view());
  pb.build(b.view());
  AlignParams plain, skip;
  skip.skip_coarse_outside = true;
  // Near the corner: level 3's patch (15 px at 8x) at the moved position has fewer than half of its
  // points inside the image, level 0's all of them.
  for (const Eigen::Vector2f& p :
       {Eigen::Vector2f(36.f, 36.f), Eigen::Vector2f(38.5f, 35.2f), Eigen::Vector2f(34.f, 39.f)}) {
    INFO("p " << p.transpose());
    SE2f T_plain(0.f, p), T_skip(0.f, p);
    const AlignStatus status = trackPatch(pa, pb, p, pattern52(), plain, 4, T_plain);
    CHECK((status == AlignStatus::kTooFewPoints || status == AlignStatus::kOutside));
    REQUIRE(trackPatch(pa, pb, p, pattern52(), skip, 4, T_skip) == AlignStatus::kConverged);
    CHECK((T_skip.translation().cast<double>() - (p.cast<double>() + t)).norm() < 0.05);
  }
  // Inside the image no level is skipped: the same result bit for bit.
  for (const Eigen::Vector2f& p : {Eigen::Vector2f(120.f, 100.f), Eigen::Vector2f(90.3f, 140.6f)}) {
    SE2f T_plain(0.f, p), T_skip(0.f, p);
    REQUIRE(trackPatch(pa, pb, p, pattern52(), plain, 4, T_plain) == AlignStatus::kConverged);
    REQUIRE(trackPatch(pa, pb, p, pattern52(), skip, 4, T_skip) == AlignStatus::kConverged);
    CHECK(T_plain.translation() == T_skip.translation());
    CHECK(T_plain.angle() == T_skip.angle());
    CHECK((T_skip.translation().cast<double>() - (p.cast<double>() + t)).norm() < 0.05);
  }
  // Level 0 is never skipped: a patch pushed mostly outside there still fails.
  for (const int levels : {1, 4}) {
    SE2f T_out(0.f, Eigen::Vector2f(-5.f, 100.f));
    CHECK(trackPatch(pa, pb, Eigen::Vector2f(100.f, 100.f), pattern52(), skip, levels, T_out) !=
          AlignStatus::kConverged);
  }
}

TEST_CASE("detector: corners of squares, one per empty cell, border, mask and threshold halving") {
  const int w = 160, h = 120;
  // Dark squares on bright background: corners at the square corners. One low-contrast square
  // (difference 12) is only found once the threshold has been halved to 10.
  GrayImage image(w, h, 200);
  const auto square = [&](int x0, int y0, int size, std::uint8_t value) {
    for (int y = y0; y < y0 + size; ++y)
      for (int x = x0; x < x0 + size; ++x) image(x, y) = value;
  };
  square(45, 45, 20, 40);   // cell (1, 1) holds its top-left corner (45, 45)
  square(85, 45, 20, 188);  // low contrast, top-left corner in cell (2, 1)
  square(2, 2, 10, 40);     // inside the 19 px border: ignored
  GridDetector detector(w, h, 40);
  DetectorParams params;
  std::vector<Eigen::Vector2f> found;
  found.reserve(100);
  detector.detect(image.view(), {}, params, 100, found);
  std::map<std::pair<int, int>, Eigen::Vector2f> by_cell;
  for (const auto& p : found) {
    const auto cell = std::pair{static_cast<int>(p.x()) / 40, static_cast<int>(p.y()) / 40};
    CHECK(by_cell.count(cell) == 0);  // at most one per cell
    by_cell[cell] = p;
    CHECK(p.x() >= 19.f);
    CHECK(p.y() >= 19.f);
  }
  REQUIRE(by_cell.count({1, 1}) == 1);
  CHECK((by_cell[{1, 1}] - Eigen::Vector2f(45.f, 45.f)).norm() <= 1.5f);
  REQUIRE(by_cell.count({2, 1}) == 1);
  CHECK((by_cell[{2, 1}] - Eigen::Vector2f(85.f, 45.f)).norm() <= 1.5f);
  CHECK(cornerResponse(image.view(), 85, 45, 20) == 0);  // too weak for the first thresholds
  CHECK(cornerResponse(image.view(), 85, 45, 10) > 0);
  // An occupied cell is not filled again.
  found.clear();
  const std::vector<Eigen::Vector2f> existing = {Eigen::Vector2f(50.f, 50.f)};
  detector.detect(image.view(), existing, params, 100, found);
  for (const auto& p : found) CHECK_FALSE((static_cast<int>(p.x()) / 40 == 1 && static_cast<int>(p.y()) / 40 == 1));
  // The safe-radius mask keeps only corners near its centre.
  found.clear();
  params.safe_radius_px = 20.f;
  params.safe_center = Eigen::Vector2f(90.f, 50.f);
  detector.detect(image.view(), {}, params, 100, found);
  REQUIRE(found.size() >= 1);
  for (const auto& p : found) CHECK((p - params.safe_center).norm() <= 20.f);
  // max_new limits the count.
  found.clear();
  params.safe_radius_px = 0.f;
  CHECK(detector.detect(image.view(), {}, params, 1, found) == 1);
}

namespace {

// A temporal step's points against the true image flow: `visible` counts the previous points whose
// true position stays inside the image (patch margin), `correct` the kept ones within 0.1 px of it
// (the 8-bit textures' rounding).
struct FlowScore {
  int visible = 0;
  int correct = 0;
  void add(const PointTrace& t, const Eigen::Vector2f& flow, int width, int height) {
    const Eigen::Vector2f truth = t.previous_px + flow;
    visible += truth.x() >= 9.f && truth.y() >= 9.f && truth.x() <= static_cast<float>(width) - 10.f &&
               truth.y() <= static_cast<float>(height) - 10.f;
    if (t.kept) correct += (t.tracked_px - truth).norm() < 0.1f;
  }
};

// A fronto-parallel textured plane at depth_m seen by a pinhole stereo pair moving sideways: image
// content moves by `flow` per frame, the right image is the left shifted by the disparity.
struct PlaneSequence {
  static constexpr int kWidth = 320, kHeight = 240;
  static constexpr double kFocal = 300.0, kBaseline = 0.11, kDepth = 2.0;
  PlaneSequence(WaveTexture texture_in, const Eigen::Vector2d& flow_in)
      : texture(std::move(texture_in)), flow(flow_in) {}

  WaveTexture texture;
  Eigen::Vector2d flow;
  double disparity = kFocal * kBaseline / kDepth;
  GrayImage left, right;

  void render(int frame) { renderAt(flow * frame); }
  // Both images with the plane moved by `shift` pixels.
  void renderAt(const Eigen::Vector2d& shift) {
    texture.render(left, kWidth, kHeight, shift.x(), shift.y());
    texture.render(right, kWidth, kHeight, shift.x() - disparity, shift.y());
  }
  DecodedStereoFrame input(int frame) const {
    DecodedStereoFrame in;
    in.images = {left, right};
    in.t_ns = frame * 50'000'000LL;
    in.frame_index = frame;
    return in;
  }
  // Renders and tracks frame k with `field` as both cameras' motion.
  void trackFrame(KltFrontend& frontend, int k, const MotionField& field, TrackedStereoFrame& frame,
                  FrontendStats& stats) {
    render(k);
    DecodedStereoFrame in = input(k);
    in.motion = {field, field};
    in.has_motion = true;
    frontend.track(in, frame, stats);
  }
  // Renders and tracks frames 0 .. frames-1, every one with the same motion field in both cameras.
  void trackWithField(KltFrontend& frontend, int frames, const MotionField& field, TrackedStereoFrame& frame,
                      FrontendStats& stats) {
    for (int k = 0; k < frames; ++k) trackFrame(frontend, k, field, frame, stats);
  }
};

}  // namespace

TEST_CASE("frontend: a capacity of 0 or above 65536 points per camera is refused before anything is allocated") {
  const StereoRig rig = voca::test::pinholeRig(320, 240, 300.0, 0.1);
  const FrontendConfig config;
  for (const int max_points : {0, 65537, 10000000}) {
    CAPTURE(max_points);
    const std::string error =
        voca::test::inputErrorOf([&] { KltFrontend frontend(config, rig, {.max_points = max_points}); });
    CHECK(error == "frontend capacity: max_points " + std::to_string(max_points) + " must be between 1 and 65536");
  }
  CHECK_NOTHROW(KltFrontend(config, rig, {.max_points = 1}));
}

TEST_CASE("frontend: tracks a translating plane with persistent ids, stereo matches at the true disparity") {
  PlaneSequence seq{WaveTexture(3), Eigen::Vector2d(1.7, -0.8)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  FrontendConfig config;
  config.prior_mode = PriorMode::kNone;
  KltFrontend frontend(config, rig, {.max_points = 200});
  TrackedStereoFrame frame;
  FrontendStats stats;
  std::map<std::uint64_t, Eigen::Vector2f> first_seen;  // id -> left position at frame 0
  std::vector<double> errors;
  for (int k = 0; k < 6; ++k) {
    seq.render(k);
    frontend.track(seq.input(k), frame, stats);
    CHECK(frame.frame_index == k);
    if (k == 0) {
      // 8 x 6 cells minus the border-only ones.
      CHECK(stats.detected >= 20);
      for (const auto& o : frame.observations[0]) first_seen[o.track_id] = o.px;
    } else {
      CHECK(stats.temporal[0].kept >= stats.temporal[0].previous * 9 / 10);
    }
    for (const auto& o : frame.observations[0]) {
      const auto it = first_seen.find(o.track_id);
      if (it == first_seen.end()) continue;
      errors.push_back((o.px.cast<double>() - (it->second.cast<double>() + seq.flow * k)).norm());
    }
    // Right observations share the ids of their left points and lie at the disparity.
    std::map<std::uint64_t, Eigen::Vector2f> left_by_id;
    for (const auto& o : frame.observations[0]) left_by_id[o.track_id] = o.px;
    int paired = 0;
    for (const auto& o : frame.observations[1]) {
      const auto it = left_by_id.find(o.track_id);
      if (it == left_by_id.end()) continue;
      ++paired;
      CHECK(std::abs(o.px.x() - (it->second.x() - seq.disparity)) < 0.1);
      CHECK(std::abs(o.px.y() - it->second.y()) < 0.1);
    }
    CHECK(paired >= static_cast<int>(frame.observations[0].size()) * 8 / 10);
    CHECK(stats.epipolar_rejected == 0);
  }
  REQUIRE(errors.size() > 100);
  std::sort(errors.begin(), errors.end());
  // Drift over 5 frames of 8-bit images: median well below 0.05 px.
  CHECK(errors[errors.size() / 2] < 0.05);
  CHECK(errors[errors.size() * 9 / 10] < 0.1);
}

TEST_CASE("frontend: stereo_max_recovered_dist2_px2 sets the left-right match's round trip alone") {
  PlaneSequence seq{WaveTexture(3), Eigen::Vector2d(1.7, -0.8)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  struct Outcome {
    int stereo_matched = 0;                              // frame 0
    std::map<std::uint64_t, Eigen::Vector2f> right;      // frame 0's right observations
    std::vector<double> disparity_errors;                // of those, against the plane's disparity
    int temporal_kept = 0;                               // frame 1, left camera
    std::map<std::uint64_t, Eigen::Vector2f> left_next;  // frame 1's left observations
  };
  // right_detail < 1: each 8x8 block of the right image keeps only this share of its detail beyond
  // the plane fitted to it (its mean and mean gradient), as a coarsely quantised block of an
  // independently encoded stream keeps its lowest frequencies; the left image stays exact.
  const auto run = [&](double temporal, double stereo, double right_detail) {
    FrontendConfig config;
    config.prior_mode = PriorMode::kNone;
    config.max_recovered_dist2_px2 = temporal;
    config.stereo_max_recovered_dist2_px2 = stereo;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    PlaneSequence sequence = seq;
    Outcome outcome;
    for (int k = 0; k < 2; ++k) {
      sequence.render(k);
      if (right_detail < 1.0) {
        const GrayImage source = sequence.right;
        for (int by = 0; by + 8 <= sequence.kHeight; by += 8) {
          for (int bx = 0; bx + 8 <= sequence.kWidth; bx += 8) {
            double mean = 0.0, gx = 0.0, gy = 0.0;
            for (int y = 0; y < 8; ++y)
              for (int x = 0; x < 8; ++x) {
                const double v = source(bx + x, by + y);
                mean += v / 64.0;
                gx += v * (x - 3.5) / 336.0;
                gy += v * (y - 3.5) / 336.0;
              }
            for (int y = 0; y < 8; ++y)
              for (int x = 0; x < 8; ++x) {
                const double plane = mean + gx * (x - 3.5) + gy * (y - 3.5);
                const double v = right_detail * source(bx + x, by + y) + (1.0 - right_detail) * plane;
                sequence.right(bx + x, by + y) = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
              }
          }
        }
      }
      frontend.track(sequence.input(k), frame, stats);
      if (k == 0) {
        outcome.stereo_matched = stats.stereo_matched;
        std::map<std::uint64_t, Eigen::Vector2f> left;
        for (const auto& o : frame.observations[0]) left[o.track_id] = o.px;
        for (const auto& o : frame.observations[1]) {
          outcome.right[o.track_id] = o.px;
          const Eigen::Vector2f& l = left.at(o.track_id);
          outcome.disparity_errors.push_back(
              Eigen::Vector2d(o.px.x() - (l.x() - sequence.disparity), o.px.y() - l.y()).norm());
        }
      } else {
        outcome.temporal_kept = stats.temporal[0].kept;
        for (const auto& o : frame.observations[0]) outcome.left_next[o.track_id] = o.px;
      }
    }
    return outcome;
  };
  const auto same = [](const std::map<std::uint64_t, Eigen::Vector2f>& a,
                       const std::map<std::uint64_t, Eigen::Vector2f>& b) {
    if (a.size() != b.size()) return false;
    for (const auto& [id, px] : a) {
      const auto it = b.find(id);
      if (it == b.end() || it->second.x() != px.x() || it->second.y() != px.y()) return false;
    }
    return true;
  };
  const Outcome basalt = run(0.25, 0.0, 1.0);
  REQUIRE(basalt.stereo_matched >= 20);
  REQUIRE(basalt.temporal_kept >= 20);
  // 0 takes the temporal tolerance, bit for bit.
  const Outcome explicit_same = run(0.25, 0.25, 1.0);
  CHECK(explicit_same.stereo_matched == basalt.stereo_matched);
  CHECK(same(explicit_same.right, basalt.right));
  CHECK(same(explicit_same.left_next, basalt.left_next));
  // A stereo tolerance no round trip meets leaves the right camera empty and the left tracks as they were.
  const Outcome no_stereo = run(0.25, 1e-30, 1.0);
  CHECK(no_stereo.stereo_matched == 0);
  CHECK(same(no_stereo.left_next, basalt.left_next));
  // A temporal tolerance no round trip meets loses the left tracks and leaves the stereo matches as they were.
  const Outcome no_temporal = run(1e-30, 0.25, 1.0);
  CHECK(no_temporal.stereo_matched == basalt.stereo_matched);
  CHECK(same(no_temporal.right, basalt.right));
  CHECK(no_temporal.temporal_kept == 0);
  // With most of the right image's detail gone a correct match strays on its round trip (the two
  // directions align different images): the looser stereo tolerance keeps more of the matches, near
  // the plane's disparity (measured: 30 and 37 of 38, median error 0.54 px, largest 1.24 px).
  const Outcome strict = run(0.25, 0.0, 0.15);
  Outcome loose = run(0.25, 1.0, 0.15);
  MESSAGE("stereo matches with 15 % of the right image's block detail: "
          << strict.stereo_matched << " at 0.25 px^2, " << loose.stereo_matched << " at 1 px^2, of "
          << basalt.stereo_matched << " with the whole detail");
  CHECK(loose.stereo_matched > strict.stereo_matched);
  REQUIRE(!loose.disparity_errors.empty());
  std::sort(loose.disparity_errors.begin(), loose.disparity_errors.end());
  MESSAGE("disparity error at 1 px^2: median " << loose.disparity_errors[loose.disparity_errors.size() / 2]
                                               << " px, max " << loose.disparity_errors.back() << " px");
  CHECK(loose.disparity_errors[loose.disparity_errors.size() / 2] < 0.75);
  CHECK(loose.disparity_errors.back() < 2.0);
}

TEST_CASE("frontend: detection_nonoverlap adds right-only tracks where the left camera does not see") {
  // 60 px of disparity at the 2 m matching depth: the right image's last ~80 px (60 px plus the
  // left image's 19 px detection border) show what the left camera does not, two 40 px grid columns.
  PlaneSequence seq{WaveTexture(5), Eigen::Vector2d(1.7, -0.8)};
  seq.disparity = 60.0;
  const StereoRig rig =
      voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.disparity * seq.kDepth / seq.kFocal);
  FrontendConfig config;
  config.prior_mode = PriorMode::kNone;
  for (const bool nonoverlap : {false, true}) {
    config.detection_nonoverlap = nonoverlap;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    std::map<std::uint64_t, Eigen::Vector2f> right_only_start;
    int right_only_tracked = 0;
    for (int k = 0; k < 6; ++k) {
      seq.render(k);
      frontend.track(seq.input(k), frame, stats);
      std::set<std::uint64_t> left_ids;
      for (const auto& o : frame.observations[0]) left_ids.insert(o.track_id);
      for (const auto& o : frame.observations[1]) {
        if (left_ids.count(o.track_id) != 0) continue;
        if (k == 0) {
          right_only_start[o.track_id] = o.px;
          CHECK(o.px.x() >= 240.f);  // only in the two non-overlapping grid columns
        } else if (const auto it = right_only_start.find(o.track_id); it != right_only_start.end()) {
          // Tracked over time in the right image like any point: it moves with the texture.
          CHECK((o.px.cast<double>() - (it->second.cast<double>() + seq.flow * k)).norm() < 0.1);
          right_only_tracked += k == 5;
        }
      }
      if (k == 0) CHECK(stats.detected_right_only == static_cast<int>(right_only_start.size()));
    }
    if (nonoverlap) {
      CHECK(right_only_start.size() >= 6);  // 2 columns x 6 rows of cells, minus border-clipped ones
      CHECK(right_only_tracked >= static_cast<int>(right_only_start.size()) * 2 / 3);
    } else {
      CHECK(right_only_start.empty());
      CHECK(stats.detected_right_only == 0);
    }
  }
}

TEST_CASE("frontend: stereo_rematch finds a left track's lost right view again, at the true disparity") {
  PlaneSequence seq{WaveTexture(3), Eigen::Vector2d(1.7, -0.8)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  FrontendConfig config;
  config.prior_mode = PriorMode::kNone;
  for (const bool rematch : {false, true}) {
    CAPTURE(rematch);
    config.stereo_rematch = rematch;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    // Frame 2's right image is flat in a band of columns: the right tracks there are lost, while
    // their left tracks go on. Frame 3 shows the texture again.
    std::set<std::uint64_t> paired_before, lost_right;  // paired in frame 1; of those, without a right view in 2
    std::vector<int> paired_per_frame;
    for (int k = 0; k < 5; ++k) {
      seq.render(k);
      if (k == 2) {
        for (int y = 0; y < seq.kHeight; ++y)
          for (int x = 80; x < 240; ++x) seq.right(x, y) = 128;
      }
      frontend.track(seq.input(k), frame, stats);
      std::map<std::uint64_t, Eigen::Vector2f> left_by_id;
      for (const auto& o : frame.observations[0]) left_by_id[o.track_id] = o.px;
      int paired = 0;
      std::uint64_t previous_id = 0;
      std::set<std::uint64_t> right_ids;
      for (const auto& o : frame.observations[1]) {
        CHECK(o.track_id > previous_id);  // the right list stays in id order (filterEpipolar merges on it)
        previous_id = o.track_id;
        right_ids.insert(o.track_id);
        const auto it = left_by_id.find(o.track_id);
        if (it == left_by_id.end()) continue;
        ++paired;
        // Before the band, and the views found again after it, lie at the disparity. (Right tracks on
        // the band's edge in frame 2 are pulled off by the flat pixels, with or without the key.)
        if (k < 2 || (k > 2 && lost_right.count(o.track_id) != 0)) {
          CHECK(std::abs(o.px.x() - (it->second.x() - seq.disparity)) < 0.1);
          CHECK(std::abs(o.px.y() - it->second.y()) < 0.1);
        }
      }
      paired_per_frame.push_back(paired);
      if (k == 2) {
        for (const auto& [id, px] : left_by_id)
          if (right_ids.count(id) == 0 && paired_before.count(id) != 0) lost_right.insert(id);
      }
      if (k == 1) {
        for (const std::uint64_t id : right_ids)
          if (left_by_id.count(id) != 0) paired_before.insert(id);
      }
      if (k == 3) {
        int found_again = 0;
        for (const std::uint64_t id : lost_right) found_again += right_ids.count(id) != 0 ? 1 : 0;
        if (rematch) {
          CHECK(found_again >= static_cast<int>(lost_right.size()) * 9 / 10);
          CHECK(stats.stereo_rematched >= found_again);
        } else {
          CHECK(found_again == 0);  // Basalt's rule: a track is matched left to right only when detected
          CHECK(stats.stereo_rematched == 0);
        }
      }
    }
    // The band held about half the image's tracks.
    CHECK(lost_right.size() >= static_cast<std::size_t>(paired_per_frame[1] / 3));
    if (rematch) {
      CHECK(paired_per_frame[3] >= paired_per_frame[1] * 9 / 10);
      CHECK(paired_per_frame[4] >= paired_per_frame[1] * 9 / 10);
    } else {
      CHECK(paired_per_frame[4] < paired_per_frame[1] * 3 / 4);
    }
  }
}

TEST_CASE("frontend: codec priors bridge large motion; none loses it; I-frames bridged") {
  // 40 px/frame is beyond the 4-level pyramid's basin for a 15 px patch at this texture scale.
  PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(40.0, 12.0)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  const Eigen::Vector2f flow = seq.flow.cast<float>();
  // Coded vectors are approximate: off by a pixel here.
  const Eigen::Vector2f coded = flow + Eigen::Vector2f(0.75f, -0.5f);
  MotionField field(seq.kWidth, seq.kHeight);

  struct Step : FlowScore {
    TemporalStats stats;
    int prior_closer = 0;  // kept points with a vector whose prior guess lies within 1.5 px of the result
  };
  const auto run = [&](PriorMode mode, bool bridge, PictureType third_type, double rescue_min_px = 0.0) {
    FrontendConfig config;
    config.prior_mode = mode;
    config.bridge_iframes = bridge;
    config.prior_rescue_min_px = rescue_min_px;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    std::array<Step, 3> result{};
    for (int k = 0; k < 3; ++k) {
      uniformField(field, seq.kWidth, seq.kHeight, coded, k == 2 ? third_type : PictureType::kP);
      seq.trackFrame(frontend, k, field, frame, stats);
      Step& step = result[static_cast<std::size_t>(k)];
      step.stats = stats.temporal[0];
      for (const PointTrace& t : frontend.traces(0)) step.add(t, flow, seq.kWidth, seq.kHeight);
      for (std::size_t i = 0; i < stats.guess_dist_prior_px.size(); ++i) {
        step.prior_closer += stats.guess_dist_prior_px[i] < 1.5f && stats.guess_dist_plain_px[i] > 40.f;
      }
    }
    return result;
  };
  const auto none = run(PriorMode::kNone, true, PictureType::kP);
  REQUIRE(none[1].visible >= 20);
  CHECK(none[1].stats.kept <= none[1].visible / 4);
  for (PriorMode mode : {PriorMode::kMv, PriorMode::kOfThenMv, PriorMode::kMvThenOf, PriorMode::kMvParallelOf}) {
    INFO("mode " << priorModeName(mode));
    const auto with_prior = run(mode, true, PictureType::kP);
    // "Most": 80 % of the points that stay in view, at the true position (8-bit texture: 0.1 px).
    CHECK(with_prior[1].correct >= with_prior[1].visible * 8 / 10);
    CHECK(with_prior[1].prior_closer >= with_prior[1].correct * 9 / 10);
    if (mode == PriorMode::kOfThenMv || mode == PriorMode::kMvParallelOf) {
      CHECK(with_prior[1].stats.rescued >= with_prior[1].correct * 3 / 4);
    } else {
      CHECK(with_prior[1].stats.rescued == 0);  // the plain track never ran before the prior
    }
    // of_then_mv keeps whatever the plain track converged to; the others keep few false tracks.
    if (mode != PriorMode::kOfThenMv) CHECK(with_prior[1].stats.kept - with_prior[1].correct <= 2);
  }
  // prior_rescue_min_px: the 41.7 px vectors may rescue under a 30 px minimum; under 50 px the prior
  // may only veto, so the points the plain track loses stay lost.
  const auto long_enough = run(PriorMode::kMvParallelOf, true, PictureType::kP, 30.0);
  CHECK(long_enough[1].correct >= long_enough[1].visible * 8 / 10);
  CHECK(long_enough[1].stats.rescued >= long_enough[1].correct * 3 / 4);
  const auto vetoing = run(PriorMode::kMvParallelOf, true, PictureType::kP, 50.0);
  CHECK(vetoing[1].stats.rescued == 0);
  CHECK(vetoing[1].stats.kept <= none[1].stats.kept);
  CHECK(vetoing[1].correct <= vetoing[1].visible / 4);
  // Frame 2 is an I-frame without vectors: bridged from frame 1's field the prior still works.
  const auto bridged = run(PriorMode::kMvParallelOf, true, PictureType::kI);
  CHECK(bridged[2].stats.with_vector == bridged[2].stats.previous);
  CHECK(bridged[2].correct >= bridged[2].visible * 8 / 10);
  const auto unbridged = run(PriorMode::kMvParallelOf, false, PictureType::kI);
  CHECK(unbridged[2].stats.with_vector == 0);
  CHECK(unbridged[2].correct <= unbridged[2].visible / 4);
}

TEST_CASE("frontend: retry_previous_flow keeps tracking a camera that speeds up beyond the pyramid's reach") {
  // The image moves 6, 12, ... 42 px in frames 1-7 (and a third of that down): from about 20 px on
  // the plain track loses its points at this texture's scale, while the previous frame's flow starts
  // the retry 6 px from the truth.
  const WaveTexture texture(5, 48, 5.0, 30.0);
  constexpr int kWidth = PlaneSequence::kWidth, kHeight = PlaneSequence::kHeight;
  const StereoRig rig = voca::test::pinholeRig(kWidth, kHeight, PlaneSequence::kFocal, PlaneSequence::kBaseline);
  struct Frame : FlowScore {
    TemporalStats stats;
    std::vector<Eigen::Vector2f> kept;
  };
  // Frames 0-7, frame k moving the image by step(k).
  // decoded: the frames are marked as decoded from video (a scope of "raw" then leaves them alone).
  const auto run = [&](PriorMode mode, bool retry, const std::function<Eigen::Vector2d(int)>& step,
                       InputScope scope = InputScope::kAlways, bool decoded = false, double min_lost_fraction = 0.0) {
    FrontendConfig config;
    config.prior_mode = mode;
    config.retry_previous_flow = retry ? scope : InputScope::kOff;
    config.retry_min_lost_fraction = min_lost_fraction;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame out;
    FrontendStats stats;
    std::vector<Frame> frames(8);
    PlaneSequence seq{texture, Eigen::Vector2d::Zero()};
    Eigen::Vector2d shift = Eigen::Vector2d::Zero();
    for (int k = 0; k < 8; ++k) {
      if (k > 0) shift += step(k);
      seq.renderAt(shift);
      DecodedStereoFrame in = seq.input(k);
      in.decoded = decoded;
      frontend.track(in, out, stats);
      Frame& f = frames[static_cast<std::size_t>(k)];
      f.stats = stats.temporal[0];
      const Eigen::Vector2f flow = step(k).cast<float>();
      for (const PointTrace& t : frontend.traces(0)) {
        f.add(t, flow, kWidth, kHeight);
        if (t.kept) f.kept.push_back(t.tracked_px);
      }
    }
    return frames;
  };
  const auto speeding_up = [](int k) { return Eigen::Vector2d(6.0 * k, 2.0 * k); };
  const auto plain = run(PriorMode::kNone, false, speeding_up);
  const auto retried = run(PriorMode::kNone, true, speeding_up);
  for (std::size_t k = 4; k < 8; ++k) {
    INFO("frame " << k);
    REQUIRE(plain[k].visible >= 20);
    CHECK(plain[k].stats.kept <= plain[k].visible / 4);
    // "Most": 80 % of the points that stay in view, at the true position, nearly all by the retry.
    CHECK(retried[k].correct >= retried[k].visible * 8 / 10);
    CHECK(retried[k].stats.flow_retried >= retried[k].correct * 3 / 4);
    CHECK(retried[k].stats.kept - retried[k].correct <= 2);
  }
  // Scope "raw": these raw frames are retried exactly as with "always"; marked decoded, not at all.
  const auto same = [](const std::vector<Frame>& x, const std::vector<Frame>& y) {
    for (std::size_t k = 0; k < x.size(); ++k) {
      if (x[k].kept != y[k].kept || x[k].stats.flow_retried != y[k].stats.flow_retried) return false;
    }
    return true;
  };
  CHECK(same(run(PriorMode::kNone, true, speeding_up, InputScope::kRawInput), retried));
  CHECK(same(run(PriorMode::kNone, true, speeding_up, InputScope::kRawInput, true), plain));
  CHECK_FALSE(same(retried, plain));
  // A prior mode on a stream without vectors (raw images): the retry is its last resort too.
  const auto prior_mode = run(PriorMode::kMvParallelOf, true, speeding_up);
  CHECK(prior_mode[7].correct >= prior_mode[7].visible * 8 / 10);
  CHECK(prior_mode[7].stats.flow_retried >= prior_mode[7].correct * 3 / 4);
  // At a steady 4 px the plain track keeps nearly every point in view, and the retry, started at the
  // truth (from frame 2; in frame 1 at the searched shift, within a coarsest-level pixel of it), adds
  // only correct ones: a point lost elsewhere than at the border now and then. A point it keeps holds
  // a detection cell, so the two runs' points differ from then on: compared over the run.
  const auto steady = [](int) { return Eigen::Vector2d(4.0, -1.5); };
  const auto steady_plain = run(PriorMode::kNone, false, steady);
  const auto steady_retried = run(PriorMode::kNone, true, steady);
  int retried_total = 0, plain_correct = 0, retried_correct = 0;
  for (std::size_t k = 1; k < 8; ++k) {
    INFO("frame " << k);
    CHECK(steady_plain[k].correct >= steady_plain[k].visible * 9 / 10);
    CHECK(steady_retried[k].correct >= steady_plain[k].correct - 2);
    CHECK(steady_retried[k].stats.kept - steady_retried[k].correct <=
          steady_plain[k].stats.kept - steady_plain[k].correct);
    retried_total += steady_retried[k].stats.flow_retried;
    plain_correct += steady_plain[k].correct;
    retried_correct += steady_retried[k].correct;
  }
  CHECK(retried_correct >= plain_correct);
  CHECK(retried_total <= 3);
  // retry_min_lost_fraction: half the points lost gates the retry. The steady frames lose a few
  // points at the border and are tracked exactly as without the retry; the fast frames lose most and
  // are retried as before.
  CHECK(same(run(PriorMode::kNone, true, steady, InputScope::kAlways, false, 0.5), steady_plain));
  const auto gated = run(PriorMode::kNone, true, speeding_up, InputScope::kAlways, false, 0.5);
  int gated_early = 0;
  for (std::size_t k = 1; k < 8; ++k) {
    INFO("frame " << k);
    const TemporalStats& t = gated[k].stats;
    // The share the guesses lost is what decides: the retried points were lost by them too.
    const int lost_by_guesses = t.previous - (t.kept - t.flow_retried);
    if (2 * lost_by_guesses < t.previous) {
      CHECK(t.flow_retried == 0);
      ++gated_early;
    }
    if (k < 4) continue;
    CHECK(gated[k].correct >= gated[k].visible * 8 / 10);
    CHECK(t.flow_retried >= gated[k].correct * 3 / 4);
  }
  CHECK(gated_early >= 1);  // the gate held in a frame of the run
}

TEST_CASE("image shift search: a whole image's translation, well beyond the pyramid's reach") {
  // Natural images have structure at every scale; so does this texture (wavelengths 5-160 px).
  const WaveTexture texture(11, 64, 5.0, 160.0);
  constexpr int kWidth = 752, kHeight = 480, kLevels = 4;
  constexpr float kCoarsestScale = 8.f;
  ImagePyramid from(kWidth, kHeight, kLevels), to(kWidth, kHeight, kLevels);
  ImageShiftSearch search(kWidth / 8 + 1, kHeight / 8 + 1);
  GrayImage image;
  texture.render(image, kWidth, kHeight, 0.0, 0.0);
  from.build(image.view());
  for (const Eigen::Vector2d& shift : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(37.0, 11.0),
                                       Eigen::Vector2d(-93.5, 40.0), Eigen::Vector2d(150.0, -100.0)}) {
    INFO("shift " << shift.transpose());
    texture.render(image, kWidth, kHeight, shift.x(), shift.y());
    to.build(image.view());
    const auto found = search.estimate(from.level(kLevels - 1), to.level(kLevels - 1), kCoarsestScale);
    REQUIRE(found.has_value());
    // Within a coarsest-level pixel, well inside the KLT pyramid's basin.
    CHECK((found->cast<double>() - shift).cwiseAbs().maxCoeff() <= kCoarsestScale);
  }
  // No answer where the images share nothing: a flat image, another scene.
  GrayImage flat(kWidth, kHeight, 90);
  to.build(flat.view());
  CHECK_FALSE(search.estimate(from.level(kLevels - 1), to.level(kLevels - 1), kCoarsestScale).has_value());
  WaveTexture(12, 64, 5.0, 160.0).render(image, kWidth, kHeight, 0.0, 0.0);
  to.build(image.view());
  CHECK_FALSE(search.estimate(from.level(kLevels - 1), to.level(kLevels - 1), kCoarsestScale).has_value());
  // Images of different sizes are not searched; nor is a level too small to hold a shift.
  ImagePyramid small(40, 30, 1);
  GrayImage small_image(40, 30, 90);
  small.build(small_image.view());
  CHECK_FALSE(search.estimate(from.level(kLevels - 1), small.level(0), kCoarsestScale).has_value());
  ImagePyramid tiny(6, 6, 1);
  GrayImage tiny_image;
  texture.render(tiny_image, 6, 6, 0.0, 0.0);
  tiny.build(tiny_image.view());
  CHECK_FALSE(search.estimate(tiny.level(0), tiny.level(0), 1.f).has_value());
}

TEST_CASE("frontend: a run that starts in fast motion is retried from the whole image's shift") {
  // 48 px per frame (and 16 down) from the first step on: beyond the plain track's pyramid, and no
  // earlier step has measured the flow the retry would start from.
  const WaveTexture texture(5, 48, 5.0, 160.0);
  constexpr int kWidth = PlaneSequence::kWidth, kHeight = PlaneSequence::kHeight;
  const StereoRig rig = voca::test::pinholeRig(kWidth, kHeight, PlaneSequence::kFocal, PlaneSequence::kBaseline);
  const Eigen::Vector2d step(48.0, 16.0);
  struct Frame : FlowScore {
    TemporalStats stats;
  };
  // Frames 0-5; reset_at: the frontend is reset before that frame (which then starts again).
  const auto run = [&](InputScope retry, int reset_at) {
    FrontendConfig config;
    config.retry_previous_flow = retry;
    config.retry_min_lost_fraction = 0.5;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame out;
    FrontendStats stats;
    std::vector<Frame> frames(6);
    PlaneSequence seq{texture, step};
    for (int k = 0; k < 6; ++k) {
      if (k == reset_at) frontend.reset();
      seq.render(k);
      frontend.track(seq.input(k), out, stats);
      Frame& f = frames[static_cast<std::size_t>(k)];
      f.stats = stats.temporal[0];
      for (const PointTrace& t : frontend.traces(0)) f.add(t, step.cast<float>(), kWidth, kHeight);
    }
    return frames;
  };
  const auto plain = run(InputScope::kOff, -1);
  const auto retried = run(InputScope::kAlways, -1);
  REQUIRE(plain[1].visible >= 20);
  CHECK(plain[1].stats.kept <= plain[1].visible / 4);
  CHECK(plain[1].stats.flow_searched == 0);
  for (std::size_t k = 1; k < 6; ++k) {
    INFO("frame " << k);
    // Most of the points that stay in view, at the true position: at 48 px a frame a fifth of them
    // lie near the border, where the coarse levels' patches leave the image.
    CHECK(retried[k].correct >= retried[k].visible * 7 / 10);
    CHECK(retried[k].stats.kept - retried[k].correct <= retried[k].stats.kept / 10);
    // The first step searches; the later ones start from the flow it measured.
    CHECK(retried[k].stats.flow_searched == (k == 1 ? 1 : 0));
    if (k == 1) CHECK(retried[k].stats.flow_retried >= retried[k].correct * 3 / 4);
  }
  // After a reset the flow is unknown again: the first step after it searches too.
  const auto after_reset = run(InputScope::kAlways, 3);
  CHECK(after_reset[3].stats.previous == 0);
  CHECK(after_reset[4].stats.flow_searched == 1);
  CHECK(after_reset[4].correct >= after_reset[4].visible * 7 / 10);
}

TEST_CASE("frontend: prior_pyramid_levels tracks motion-vector guesses on the finest levels only") {
  // 12 px/frame: the previous position needs the coarse levels, a vector within a pixel does not.
  // 40 px/frame: beyond the plain track's basin (see the bridging test), only the prior tracks.
  for (const double speed : {12.0, 40.0}) {
    PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(speed, 5.0)};
    const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
    const Eigen::Vector2f flow = seq.flow.cast<float>();
    MotionField field(seq.kWidth, seq.kHeight);
    struct Outcome : FlowScore {
      int kept = 0;
    };
    const auto run = [&](int prior_pyramid_levels, const Eigen::Vector2f& vector_error,
                         PriorMode mode = PriorMode::kMv) {
      FrontendConfig config;
      config.prior_mode = mode;
      config.prior_pyramid_levels = prior_pyramid_levels;
      KltFrontend frontend(config, rig, {.max_points = 200});
      uniformField(field, seq.kWidth, seq.kHeight, flow + vector_error, PictureType::kP);
      TrackedStereoFrame frame;
      FrontendStats stats;
      seq.trackWithField(frontend, 2, field, frame, stats);
      Outcome outcome;
      outcome.kept = stats.temporal[0].kept;
      for (const PointTrace& t : frontend.traces(0)) outcome.add(t, flow, seq.kWidth, seq.kHeight);
      return outcome;
    };
    // A vector within a pixel: level 0 alone finds the true position (80 %, as in the test above).
    const Outcome close = run(0, Eigen::Vector2f(0.75f, -0.5f));
    REQUIRE(close.visible >= 20);
    CHECK(close.correct >= close.visible * 8 / 10);
    CHECK(close.kept - close.correct <= 2);
    // Off by 5 px: beyond level 0's reach (about 2 px; 1 of 47 here), within the whole pyramid's, so the
    // key is what decides.
    const Outcome far_finest = run(0, Eigen::Vector2f(5.f, 0.f));
    const Outcome far_all = run(-1, Eigen::Vector2f(5.f, 0.f));
    CHECK(far_finest.correct <= far_finest.visible / 4);
    CHECK(far_all.correct >= far_all.visible * 3 / 4);  // 38 of 47 here; the rest leave the image or drift
    // of_then_mv's prior rescues what the plain track lost: it keeps the whole pyramid whatever the key.
    const Outcome rescue_finest = run(0, Eigen::Vector2f(5.f, 0.f), PriorMode::kOfThenMv);
    const Outcome rescue_all = run(-1, Eigen::Vector2f(5.f, 0.f), PriorMode::kOfThenMv);
    CHECK(rescue_finest.correct == rescue_all.correct);
    CHECK(rescue_finest.kept == rescue_all.kept);
    CHECK(rescue_finest.correct >= rescue_finest.visible * 3 / 4);
  }
}

TEST_CASE("frontend: a frame without vectors after motion-vector tracks builds the coarse templates it needs") {
  // mv with prior_pyramid_levels 0: the round trips of frames 1-2 run on level 0 and build only its
  // templates. Frame 3 is an I-frame, unbridged: every point falls back to the plain track, whose
  // 12 px motion needs the coarse levels (see the test above), so their templates must be built then,
  // from the previous image at each point's position. Missing, the coarse levels would be skipped as
  // invalid and the plain track would stay in level 0's basin.
  PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(12.0, 5.0)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  const Eigen::Vector2f flow = seq.flow.cast<float>();
  const Eigen::Vector2f coded = flow + Eigen::Vector2f(0.5f, -0.25f);
  MotionField field(seq.kWidth, seq.kHeight);
  FrontendConfig config;
  config.prior_mode = PriorMode::kMv;
  config.prior_pyramid_levels = 0;
  config.bridge_iframes = false;
  KltFrontend frontend(config, rig, {.max_points = 200});
  TrackedStereoFrame frame;
  FrontendStats stats;
  for (int k = 0; k < 4; ++k) {
    uniformField(field, seq.kWidth, seq.kHeight, coded, k == 3 ? PictureType::kI : PictureType::kP);
    seq.trackFrame(frontend, k, field, frame, stats);
    if (k == 0) continue;
    INFO("frame " << k);
    FlowScore score;
    for (const PointTrace& t : frontend.traces(0)) score.add(t, flow, seq.kWidth, seq.kHeight);
    CHECK(stats.temporal[0].with_vector == (k == 3 ? 0 : stats.temporal[0].previous));
    CHECK(stats.temporal[0].tracked_plain == (k == 3 ? stats.temporal[0].kept : 0));
    REQUIRE(score.visible >= 20);
    // Frame 3: 48 of 64 at the true position (plain KLT at 12 px); 10 with the coarse levels missing.
    CHECK(score.correct >= score.visible * 2 / 3);
    CHECK(stats.temporal[0].kept - score.correct <= 2);
  }
}

TEST_CASE("frontend: backward_pyramid_levels runs the round trip on the finest levels only") {
  // 12 px/frame: the forward track needs the coarse levels; the round trip, started where undoing
  // them puts it, needs only the finest ones.
  PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(12.0, 5.0)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  const Eigen::Vector2f flow = seq.flow.cast<float>();
  struct Outcome {
    std::map<std::uint64_t, PointTrace> traces;
    int kept = 0, correct = 0;
  };
  // Frames 0 and 1 of the plane; with `swap`, frame 1 shows another texture, so no track is right.
  const auto run = [&](int backward_pyramid_levels, bool swap) {
    FrontendConfig config;
    config.prior_mode = PriorMode::kNone;
    config.backward_pyramid_levels = backward_pyramid_levels;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    PlaneSequence sequence = seq;
    for (int k = 0; k < 2; ++k) {
      if (swap && k == 1) sequence.texture = WaveTexture(17, 48, 5.0, 30.0);
      sequence.render(k);
      frontend.track(sequence.input(k), frame, stats);
    }
    Outcome outcome;
    outcome.kept = stats.temporal[0].kept;
    for (const PointTrace& t : frontend.traces(0)) {
      outcome.traces[t.track_id] = t;
      if (t.kept) outcome.correct += (t.tracked_px - (t.previous_px + flow)).norm() < 0.1f;
    }
    return outcome;
  };
  const Outcome all = run(-1, false);
  REQUIRE(all.traces.size() >= 20);
  for (const int levels : {0, 1}) {
    CAPTURE(levels);
    const Outcome fine = run(levels, false);
    // Only the check changes: every forward track ends where it did, bit for bit.
    REQUIRE(fine.traces.size() == all.traces.size());
    for (const auto& [id, t] : fine.traces) {
      const PointTrace& reference = all.traces.at(id);
      CHECK(t.tracked_px.x() == reference.tracked_px.x());
      CHECK(t.tracked_px.y() == reference.tracked_px.y());
    }
    // And on this clean motion it keeps what the whole round trip keeps (all correct).
    CHECK(fine.kept == all.kept);
    CHECK(fine.correct == all.correct);
    CHECK(fine.correct >= fine.kept - 1);
    // Another texture in frame 1: the shortened round trip still rejects most of the forward tracks'
    // false matches, if fewer than the whole one (measured: it keeps 5-6 of 48, the whole one 2).
    const Outcome wrong_all = run(-1, true);
    const Outcome wrong_fine = run(levels, true);
    MESSAGE("kept after a texture swap: whole round trip " << wrong_all.kept << ", finest levels " << wrong_fine.kept
                                                           << " of " << wrong_fine.traces.size());
    CHECK(wrong_fine.correct == 0);
    CHECK(wrong_all.kept <= static_cast<int>(wrong_all.traces.size()) / 10);
    CHECK(wrong_fine.kept <= static_cast<int>(wrong_fine.traces.size()) / 6);
  }
}

TEST_CASE("frontend: a zero motion vector tracks exactly as no prior (the prior track runs once)") {
  PlaneSequence seq{WaveTexture(3), Eigen::Vector2d(1.7, -0.8)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  MotionField field(seq.kWidth, seq.kHeight);
  uniformField(field, seq.kWidth, seq.kHeight, Eigen::Vector2f::Zero(), PictureType::kP);
  std::map<PriorMode, std::vector<KeypointObservation>> tracks;
  std::map<PriorMode, TemporalStats> temporal;
  for (PriorMode mode : kAllPriorModes) {
    FrontendConfig config;
    config.prior_mode = mode;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    seq.trackWithField(frontend, 3, field, frame, stats);
    tracks[mode] = frame.observations[0];
    temporal[mode] = stats.temporal[0];
  }
  const std::vector<KeypointObservation>& none = tracks[PriorMode::kNone];
  REQUIRE(none.size() >= 20);
  for (PriorMode mode : kAllPriorModes) {
    INFO("mode " << priorModeName(mode));
    const std::vector<KeypointObservation>& other = tracks[mode];
    REQUIRE(other.size() == none.size());
    for (std::size_t i = 0; i < none.size(); ++i) {
      CHECK(other[i].track_id == none[i].track_id);
      CHECK(other[i].px == none[i].px);  // bit for bit
    }
    CHECK(temporal[mode].consensus_rejections == 0);
    CHECK(temporal[mode].rescued == 0);
  }
  // In parallel both guesses count as tracked, the plain one's result standing for the prior's.
  CHECK(temporal[PriorMode::kMvParallelOf].tracked_prior == temporal[PriorMode::kMvParallelOf].tracked_plain);
}

TEST_CASE("frontend: a wrong motion vector onto a repeated pattern is caught by the consensus check") {
  // On a texture with period 24 px, a vector off by one period leads the prior track to an equally
  // good match 24 px away; forward-backward cannot see it (the backward track starts from the
  // negated prior), only the disagreement with the plain track does.
  PlaneSequence seq{WaveTexture::periodic(9, 24), Eigen::Vector2d(1.2, 0.6)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  const Eigen::Vector2f wrong = seq.flow.cast<float>() + Eigen::Vector2f(24.f, 0.f);
  MotionField field(seq.kWidth, seq.kHeight);
  uniformField(field, seq.kWidth, seq.kHeight, wrong, PictureType::kP);
  std::map<PriorMode, TemporalStats> result;
  for (PriorMode mode : {PriorMode::kMv, PriorMode::kMvParallelOf}) {
    FrontendConfig config;
    config.prior_mode = mode;
    KltFrontend frontend(config, rig, {.max_points = 200});
    TrackedStereoFrame frame;
    FrontendStats stats;
    seq.trackWithField(frontend, 2, field, frame, stats);
    result[mode] = stats.temporal[0];
    if (mode == PriorMode::kMvParallelOf) {
      for (const PointTrace& t : frontend.traces(0)) {
        if (t.kept) CHECK((t.tracked_px - t.previous_px - seq.flow.cast<float>()).norm() < 0.1f);
      }
    }
  }
  const TemporalStats& mv = result[PriorMode::kMv];
  const TemporalStats& parallel = result[PriorMode::kMvParallelOf];
  REQUIRE(mv.previous >= 15);
  // MV alone keeps most points, at the wrong copy of the pattern.
  CHECK(mv.kept >= mv.previous / 2);
  // In parallel, the wrong-copy matches are rejected by consensus.
  CHECK(parallel.consensus_rejections >= parallel.previous / 2);
  CHECK(parallel.rescued == 0);
}

TEST_CASE(
    "frontend: thin_when_full_px drops the younger of two close tracks when full, in both cameras, for new points") {
  PlaneSequence seq{WaveTexture(3), Eigen::Vector2d(0.6, -0.4)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  struct Outcome {
    TrackedStereoFrame first, second;
    FrontendStats stats;  // of the second frame
  };
  const auto run = [&](double distance, int max_points) {
    FrontendConfig config;
    config.prior_mode = PriorMode::kNone;
    config.thin_when_full_px = distance;
    KltFrontend frontend(config, rig, {.max_points = max_points});
    Outcome o;
    FrontendStats stats;
    PlaneSequence sequence = seq;
    sequence.render(0);
    frontend.track(sequence.input(0), o.first, stats);
    sequence.render(1);
    frontend.track(sequence.input(1), o.second, o.stats);
    return o;
  };
  // One corner per 40 px cell: corners of neighbouring cells can lie closer than 30 px.
  constexpr double kDistance = 30.0;
  // With room to spare nothing is dropped: the same tracks as without the key.
  const Outcome roomy = run(0.0, 200);
  const Outcome roomy_thin = run(kDistance, 200);
  CHECK(roomy_thin.stats.thinned == 0);
  REQUIRE(roomy_thin.second.observations[0].size() == roomy.second.observations[0].size());
  for (std::size_t i = 0; i < roomy.second.observations[0].size(); ++i) {
    CHECK(roomy_thin.second.observations[0][i].track_id == roomy.second.observations[0][i].track_id);
    CHECK(roomy_thin.second.observations[0][i].px == roomy.second.observations[0][i].px);
  }
  // The capacity of the first frame's points: every one survives the small motion, the tracker is
  // full and detects nothing.
  const int capacity = static_cast<int>(roomy.first.observations[0].size());
  const Outcome full = run(0.0, capacity);
  REQUIRE(full.stats.temporal[0].kept == capacity);
  CHECK(full.stats.detected == 0);
  CHECK(full.stats.thinned == 0);
  // The rule written out on those tracks: ids ascend with age; a track is kept unless an older
  // kept one lies closer than the distance.
  const std::vector<KeypointObservation>& tracked = full.second.observations[0];
  std::vector<KeypointObservation> expected;
  for (const auto& t : tracked) {
    const bool crowded = std::any_of(expected.begin(), expected.end(), [&](const KeypointObservation& e) {
      return (e.px - t.px).norm() < static_cast<float>(kDistance);
    });
    if (!crowded) expected.push_back(t);
  }
  REQUIRE(expected.size() >= 5);
  REQUIRE(expected.size() < tracked.size());
  const Outcome thin = run(kDistance, capacity);
  std::set<std::uint64_t> first_ids;
  for (const auto& o : thin.first.observations[0]) first_ids.insert(o.track_id);
  const auto tracks_of_first = [&](const std::vector<KeypointObservation>& observations) {
    std::vector<KeypointObservation> out;
    for (const auto& o : observations)
      if (first_ids.count(o.track_id) != 0) out.push_back(o);
    return out;
  };
  const std::vector<KeypointObservation> kept = tracks_of_first(thin.second.observations[0]);
  REQUIRE(kept.size() == expected.size());
  for (std::size_t i = 0; i < kept.size(); ++i) {
    CHECK(kept[i].track_id == expected[i].track_id);
    CHECK(kept[i].px == expected[i].px);
  }
  CHECK(thin.stats.thinned == static_cast<int>(tracked.size() - expected.size()));
  // The room they leave goes to new points in empty cells.
  CHECK(thin.stats.detected > 0);
  CHECK(thin.stats.detected <= thin.stats.thinned);
  // The right camera keeps the right observations of the kept tracks only.
  std::set<std::uint64_t> kept_ids;
  for (const auto& o : kept) kept_ids.insert(o.track_id);
  std::size_t right_expected = 0;
  for (const auto& o : full.second.observations[1]) right_expected += kept_ids.count(o.track_id);
  const std::vector<KeypointObservation> right_kept = tracks_of_first(thin.second.observations[1]);
  CHECK(right_kept.size() == right_expected);
  for (const auto& o : right_kept) CHECK(kept_ids.count(o.track_id) == 1);
}

TEST_CASE("frontend: prior_agree_radius_px takes a vector landing next to the plain result as agreement, untracked") {
  PlaneSequence seq{WaveTexture(3), Eigen::Vector2d(1.7, -0.8)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  const Eigen::Vector2f flow = seq.flow.cast<float>();
  MotionField field(seq.kWidth, seq.kHeight);
  struct Outcome {
    std::vector<KeypointObservation> tracks;
    TemporalStats temporal;
  };
  const auto run = [&](double radius, const Eigen::Vector2f& vector) {
    FrontendConfig config;
    config.prior_mode = PriorMode::kMvParallelOf;
    config.prior_pyramid_levels = 1;  // as the euroc config: the prior track differs from the plain one
    config.prior_agree_radius_px = radius;
    KltFrontend frontend(config, rig, {.max_points = 200});
    uniformField(field, seq.kWidth, seq.kHeight, vector, PictureType::kP);
    TrackedStereoFrame frame;
    FrontendStats stats;
    seq.trackWithField(frontend, 3, field, frame, stats);
    return Outcome{frame.observations[0], stats.temporal[0]};
  };
  // A vector 0.36 px off: every prior track would converge where the plain one did. With the radius
  // none of them runs, and the output is the same bit for bit (the plain result is what is kept).
  const Eigen::Vector2f close = flow + Eigen::Vector2f(0.3f, -0.2f);
  const Outcome tracked = run(0.0, close);
  const Outcome confirmed = run(1.0, close);
  REQUIRE(tracked.tracks.size() >= 20);
  CHECK(tracked.temporal.prior_confirmed == 0);
  CHECK(tracked.temporal.consensus_rejections == 0);
  CHECK(confirmed.temporal.prior_confirmed >= confirmed.temporal.kept * 9 / 10);
  CHECK(confirmed.temporal.tracked_prior == tracked.temporal.tracked_prior);
  CHECK(confirmed.temporal.kept == tracked.temporal.kept);
  REQUIRE(confirmed.tracks.size() == tracked.tracks.size());
  for (std::size_t i = 0; i < tracked.tracks.size(); ++i) {
    CHECK(confirmed.tracks[i].track_id == tracked.tracks[i].track_id);
    CHECK(confirmed.tracks[i].px == tracked.tracks[i].px);
  }
  // A vector 3 px off lands outside the radius: the prior track runs, and agrees.
  const Outcome far = run(1.0, flow + Eigen::Vector2f(3.f, 0.f));
  CHECK(far.temporal.prior_confirmed == 0);
  CHECK(far.temporal.tracked_prior >= far.temporal.kept * 9 / 10);
  CHECK(far.temporal.kept == tracked.temporal.kept);
}

TEST_CASE("frontend: prior_agree_radius_px leaves the consensus check of a wrong vector in place") {
  // The repeated pattern of the consensus test: the wrong vector lands a period (24 px) away from
  // the plain result, far outside the radius, so the prior track runs and the disagreement shows.
  PlaneSequence seq{WaveTexture::periodic(9, 24), Eigen::Vector2d(1.2, 0.6)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  MotionField field(seq.kWidth, seq.kHeight);
  uniformField(field, seq.kWidth, seq.kHeight, seq.flow.cast<float>() + Eigen::Vector2f(24.f, 0.f), PictureType::kP);
  FrontendConfig config;
  config.prior_mode = PriorMode::kMvParallelOf;
  config.prior_agree_radius_px = 1.0;
  KltFrontend frontend(config, rig, {.max_points = 200});
  TrackedStereoFrame frame;
  FrontendStats stats;
  seq.trackWithField(frontend, 2, field, frame, stats);
  const TemporalStats& t = stats.temporal[0];
  REQUIRE(t.previous >= 15);
  CHECK(t.prior_confirmed == 0);
  CHECK(t.consensus_rejections >= t.previous / 2);
}

TEST_CASE("frontend: codec confidence: vectors of small, inconsistent or poorly predicting blocks count as absent") {
  // 40 px/frame: only a trusted prior tracks (mode mv falls back to the previous position, which
  // loses the motion), so what is distrusted shows in both the counter and the tracks.
  PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(40.0, 12.0)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  const Eigen::Vector2f flow = seq.flow.cast<float>();
  const Eigen::Vector2f coded = flow + Eigen::Vector2f(0.75f, -0.5f);
  struct Outcome {
    TemporalStats stats;
    int correct = 0;        // kept points within 0.1 px of the true position
    int in_odd_blocks = 0;  // previous points in a block whose vector `odd` replaced
    int visible = 0;        // previous points whose true position stays inside the image
  };
  // `odd` returns a replacement vector for a block at (x, y), or nothing to keep `coded`.
  // `qp`, when given, sets the quantiser of the block at (x, y).
  const auto run = [&](const FrontendConfig& base, int block_px,
                       const std::function<std::optional<Eigen::Vector2f>(int, int)>& odd,
                       const std::function<int(int, int)>& qp = {}) {
    FrontendConfig config = base;
    config.prior_mode = PriorMode::kMv;
    KltFrontend frontend(config, rig, {.max_points = 200});
    MotionField field(seq.kWidth, seq.kHeight);
    TrackedStereoFrame frame;
    FrontendStats stats;
    for (int k = 0; k < 2; ++k) {
      seq.render(k);
      DecodedStereoFrame in = seq.input(k);
      field.reset(seq.kWidth, seq.kHeight, PictureType::kP);
      for (int y = 0; y < seq.kHeight; y += block_px) {
        for (int x = 0; x < seq.kWidth; x += block_px) {
          const Eigen::Vector2f v = odd(x, y).value_or(coded);
          field.addBlock(x, y, block_px, block_px, v.x(), v.y());
          if (qp) field.setQp(x, y, block_px, block_px, qp(x, y));
        }
      }
      field.finalize();
      in.motion = {field, field};
      in.has_motion = true;
      frontend.track(in, frame, stats);
    }
    FlowScore score;
    int in_odd_blocks = 0;
    for (const PointTrace& t : frontend.traces(0)) {
      score.add(t, flow, seq.kWidth, seq.kHeight);
      const int bx = static_cast<int>(std::lround(t.previous_px.x())) / block_px * block_px;
      const int by = static_cast<int>(std::lround(t.previous_px.y())) / block_px * block_px;
      in_odd_blocks += odd(bx, by).has_value();
    }
    return Outcome{stats.temporal[0], score.correct, in_odd_blocks, score.visible};
  };
  const auto none = [](int, int) { return std::optional<Eigen::Vector2f>(); };
  const FrontendConfig defaults;

  SUBCASE("all checks off: every vector is used") {
    const auto [stats, correct, odd_points, visible] = run(defaults, 8, none);
    REQUIRE(stats.previous >= 20);
    CHECK(stats.distrusted == 0);
    CHECK(correct >= visible * 8 / 10);
  }
  SUBCASE("prior_min_block_px: 8x8 partitions distrusted at 16, trusted at 8") {
    FrontendConfig config;
    config.prior_min_block_px = 16;
    const auto [stats, correct, odd_points, visible] = run(config, 8, none);
    REQUIRE(stats.previous >= 20);
    CHECK(stats.distrusted == stats.with_vector);
    CHECK(correct <= stats.previous / 4);
    config.prior_min_block_px = 8;
    CHECK(run(config, 8, none).stats.distrusted == 0);
  }
  SUBCASE("prior_reject_inconsistent: a block disagreeing with its neighbours is distrusted, the rest not") {
    FrontendConfig config;
    config.prior_reject_inconsistent = true;
    // One block in every 4x4 group points 20 px the wrong way.
    const auto wrong = [&](int x, int y) {
      return x % 64 == 16 && y % 64 == 16 ? std::optional<Eigen::Vector2f>(coded + Eigen::Vector2f(-20.f, 9.f))
                                          : std::optional<Eigen::Vector2f>();
    };
    const auto [stats, correct, odd_points, visible] = run(config, 16, wrong);
    REQUIRE(stats.previous >= 20);
    REQUIRE(odd_points >= 1);
    CHECK(stats.distrusted == odd_points);
    CHECK(correct >= (visible - odd_points) * 8 / 10);
  }
  SUBCASE("prior_max_qp: exactly the vectors of blocks quantised above the threshold are distrusted") {
    // One macroblock in four (a checkerboard of 2x2 groups) at QP 40, the rest at 30. `odd` keeps
    // the coded vector and only marks the QP-40 blocks, so odd_points counts the points in them.
    const auto coarse = [](int x, int y) { return (x / 32 + y / 32) % 2 == 0 && (x / 16) % 2 == 0; };
    const auto mark = [&](int x, int y) {
      return coarse(x, y) ? std::optional<Eigen::Vector2f>(coded) : std::optional<Eigen::Vector2f>();
    };
    const auto qp = [&](int x, int y) { return coarse(x, y) ? 40 : 30; };
    FrontendConfig config;
    config.prior_max_qp = 35;
    const auto [stats, correct, odd_points, visible] = run(config, 16, mark, qp);
    REQUIRE(stats.previous >= 20);
    REQUIRE(odd_points >= 3);
    REQUIRE(odd_points < stats.with_vector);
    CHECK(stats.distrusted == odd_points);
    CHECK(correct >= (visible - odd_points) * 8 / 10);
    CHECK(correct <= visible - odd_points / 2);  // the distrusted ones lose the 40 px motion
    // At the QP itself a vector is kept; above every QP nothing is distrusted, and 0 turns the check off.
    config.prior_max_qp = 40;
    CHECK(run(config, 16, mark, qp).stats.distrusted == 0);
    config.prior_max_qp = 29;
    const TemporalStats all = run(config, 16, mark, qp).stats;
    CHECK(all.distrusted == all.with_vector);
    config.prior_max_qp = 0;
    CHECK(run(config, 16, mark, qp).stats.distrusted == 0);
    // Vectors without a quantiser (not exported) are trusted whatever the threshold.
    config.prior_max_qp = 1;
    CHECK(run(config, 16, mark).stats.distrusted == 0);
  }
  SUBCASE("prior_max_residual_px: a vector whose prediction does not match is distrusted, a good one kept") {
    FrontendConfig config;
    config.prior_max_residual_px = 1.5;
    const auto good = run(config, 16, none);
    REQUIRE(good.stats.previous >= 20);
    // Distrusted: at most the points the vector moves out of view (no neighbourhood there) and a few.
    const int leaving = good.stats.previous - good.visible;
    CHECK(good.stats.distrusted <= leaving + good.stats.with_vector / 10);
    CHECK(good.correct >= good.visible * 8 / 10);
    const auto off = [&](int, int) { return std::optional<Eigen::Vector2f>(coded + Eigen::Vector2f(-13.f, 7.f)); };
    const auto bad = run(config, 16, off);
    CHECK(bad.stats.distrusted >= bad.stats.with_vector * 9 / 10);
  }
}

TEST_CASE("frontend: the work items of a frame, on two threads or in any order, give track()'s results bit for bit") {
  // The image moves 6, 12, ... 30 px in frames 1-5 (and a third of that down): beyond the pyramid's
  // reach from about 20 px on, where the previous-flow retry keeps the tracks. The vectors are the
  // first frame's motion a pixel off, so the prior tracks run and agree at first, then fail.
  PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(6.0, 2.0)};
  const StereoRig rig = voca::test::pinholeRig(seq.kWidth, seq.kHeight, seq.kFocal, seq.kBaseline);
  FrontendConfig config;
  config.prior_mode = PriorMode::kMvParallelOf;
  config.retry_previous_flow = InputScope::kAlways;
  MotionField field(seq.kWidth, seq.kHeight);
  uniformField(field, seq.kWidth, seq.kHeight, seq.flow.cast<float>() + Eigen::Vector2f(1.f, -0.5f), PictureType::kP);
  // kConcurrent: as the frontend stage with its helper thread, which runs the odd items while the
  // calling thread runs the even ones.
  enum class Order { kTrack, kConcurrent, kReversed };
  struct Frame {
    TrackedStereoFrame tracked;
    FrontendStats stats;
    std::vector<PointTrace> left_traces;
  };
  const auto run = [&](Order order) {
    KltFrontend frontend(config, rig, {.max_points = 200});
    std::vector<Frame> frames(6);
    Eigen::Vector2d position = Eigen::Vector2d::Zero();
    for (int k = 0; k < 6; ++k) {
      position += k * seq.flow;
      seq.renderAt(position);
      DecodedStereoFrame in = seq.input(k);
      in.motion = {field, field};
      in.has_motion = true;
      Frame& out = frames[static_cast<std::size_t>(k)];
      if (order == Order::kTrack) {
        frontend.track(in, out.tracked, out.stats);
      } else {
        const int items = frontend.beginFrame(in, out.stats);
        REQUIRE(items >= 2);
        if (order == Order::kConcurrent) {
          std::thread helper([&] {
            for (int item = 1; item < items; item += 2) frontend.runItem(item, in);
          });
          for (int item = 0; item < items; item += 2) frontend.runItem(item, in);
          helper.join();
        } else {
          for (int item = items - 1; item >= 0; --item) frontend.runItem(item, in);
        }
        frontend.endFrame(in, out.tracked, out.stats);
      }
      out.left_traces.assign(frontend.traces(0).begin(), frontend.traces(0).end());
    }
    return frames;
  };
  const std::vector<Frame> reference = run(Order::kTrack);
  // The sequence exercises what the cameras' tracking writes: priors, kept tracks, the retry.
  int prior_tracks = 0, retried = 0;
  for (const Frame& f : reference) {
    for (const TemporalStats& t : f.stats.temporal) {
      prior_tracks += t.tracked_prior;
      retried += t.flow_retried;
    }
  }
  CHECK(prior_tracks > 100);
  CHECK(retried > 10);
  CHECK(reference.back().tracked.observations[1].size() > 30);
  for (const Order order : {Order::kConcurrent, Order::kReversed}) {
    const std::vector<Frame> frames = run(order);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      INFO("order " << static_cast<int>(order) << ", frame " << k);
      const Frame& a = reference[k];
      const Frame& b = frames[k];
      for (std::size_t c = 0; c < 2; ++c) {
        const auto& oa = a.tracked.observations[c];
        const auto& ob = b.tracked.observations[c];
        REQUIRE(oa.size() == ob.size());
        for (std::size_t i = 0; i < oa.size(); ++i) {
          CHECK(oa[i].track_id == ob[i].track_id);
          CHECK(oa[i].px == ob[i].px);
        }
        CHECK(a.stats.temporal[c] == b.stats.temporal[c]);
        CHECK(a.stats.bridged[c] == b.stats.bridged[c]);
      }
      CHECK(a.stats.guess_dist_plain_px == b.stats.guess_dist_plain_px);
      CHECK(a.stats.guess_dist_prior_px == b.stats.guess_dist_prior_px);
      CHECK(a.stats.detected == b.stats.detected);
      CHECK(a.stats.stereo_matched == b.stats.stereo_matched);
      CHECK(a.stats.epipolar_rejected == b.stats.epipolar_rejected);
      CHECK(a.stats.num_left == b.stats.num_left);
      CHECK(a.stats.num_right == b.stats.num_right);
      REQUIRE(a.left_traces.size() == b.left_traces.size());
      for (std::size_t i = 0; i < a.left_traces.size(); ++i) {
        CHECK(a.left_traces[i].track_id == b.left_traces[i].track_id);
        CHECK(a.left_traces[i].tracked_px == b.left_traces[i].tracked_px);
        CHECK(a.left_traces[i].kept == b.left_traces[i].kept);
      }
    }
  }
}

TEST_CASE(
    "temporal tracking: one camera's points in two shares, split anywhere, on two threads or in either order, give "
    "one share's results bit for bit") {
  // The sequence of the test above, one camera: prior tracks that agree at first, then fail, and the
  // previous-flow retry.
  PlaneSequence seq{WaveTexture(5, 48, 5.0, 30.0), Eigen::Vector2d(6.0, 2.0)};
  FrontendConfig config;
  config.prior_mode = PriorMode::kMvParallelOf;
  config.retry_previous_flow = InputScope::kAlways;
  MotionField field(seq.kWidth, seq.kHeight);
  uniformField(field, seq.kWidth, seq.kHeight, seq.flow.cast<float>() + Eigen::Vector2f(1.f, -0.5f), PictureType::kP);
  const RoundTripTracker klt(config);
  constexpr int kMaxPoints = 200;
  struct Step {
    std::vector<std::uint64_t> ids;
    std::vector<Eigen::Vector2f> points;
    TemporalStats stats;
    std::vector<PointTrace> traces;
  };
  enum class Order { kConcurrent, kSecondFirst };
  const auto run = [&](double split_fraction, Order order) {
    CameraTracks camera(kMaxPoints, TemporalTracker::kScratchSlots, seq.kWidth, seq.kHeight, config.pyramid_levels + 1,
                        false);
    TemporalTracker temporal(config, klt, kMaxPoints, seq.kWidth, seq.kHeight, camera);
    std::vector<Step> steps;
    Eigen::Vector2d position = Eigen::Vector2d::Zero();
    for (int k = 0; k < 6; ++k) {
      position += k * seq.flow;
      seq.renderAt(position);
      camera.advance(seq.input(k).images[0].view(), false);
      temporal.begin(&field, 0, k > 0, true, camera);
      if (k == 0) {
        std::uint64_t id = 1;
        for (int y = 30; y < seq.kHeight - 30; y += 20) {
          for (int x = 30; x < seq.kWidth - 30; x += 20)
            camera.addDetected(id++, Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y)), klt.pattern());
        }
        continue;
      }
      const std::size_t n = camera.size();
      const auto split = static_cast<std::size_t>(std::lround(split_fraction * static_cast<double>(n)));
      if (order == Order::kConcurrent) {
        std::thread second([&] { temporal.trackShare(1, split, n, camera); });
        temporal.trackShare(0, 0, split, camera);
        second.join();
      } else {
        temporal.trackShare(1, split, n, camera);
        temporal.trackShare(0, 0, split, camera);
      }
      temporal.finish(camera);
      steps.push_back(
          {camera.ids, camera.points, temporal.stats(), {temporal.traces().begin(), temporal.traces().end()}});
    }
    return steps;
  };
  const std::vector<Step> reference = run(1.0, Order::kSecondFirst);
  // The sequence exercises what a share writes: prior tracks, kept tracks, retry candidates.
  int prior_tracks = 0, retried = 0;
  for (const Step& step : reference) {
    prior_tracks += step.stats.tracked_prior;
    retried += step.stats.flow_retried;
  }
  CHECK(prior_tracks > 200);
  CHECK(retried > 50);
  CHECK(reference.back().ids.size() > 30);
  for (const double split : {0.0, 0.37, 0.5, 1.0}) {
    for (const Order order : {Order::kConcurrent, Order::kSecondFirst}) {
      const std::vector<Step> steps = run(split, order);
      REQUIRE(steps.size() == reference.size());
      for (std::size_t k = 0; k < steps.size(); ++k) {
        INFO("split " << split << ", order " << static_cast<int>(order) << ", step " << k);
        CHECK(steps[k].ids == reference[k].ids);
        CHECK(steps[k].points == reference[k].points);
        CHECK(steps[k].stats == reference[k].stats);
        REQUIRE(steps[k].traces.size() == reference[k].traces.size());
        for (std::size_t i = 0; i < steps[k].traces.size(); ++i) {
          CHECK(steps[k].traces[i].track_id == reference[k].traces[i].track_id);
          CHECK(steps[k].traces[i].tracked_px == reference[k].traces[i].tracked_px);
          CHECK(steps[k].traces[i].kept == reference[k].traces[i].kept);
        }
      }
    }
  }
}

TEST_CASE("frontend: constructor and inputs are checked") {
  const StereoRig rig = voca::test::pinholeRig(320, 240, 300.0, 0.1);
  FrontendConfig config;
  config.pattern = 30;
  CHECK_THROWS_AS(KltFrontend(config, rig), InputError);
  StereoRig mono = rig;
  mono.cameras.pop_back();
  CHECK_THROWS_AS(KltFrontend(FrontendConfig{}, mono), InputError);
  KltFrontend frontend(FrontendConfig{}, rig);
  GrayImage small(100, 100, 0);
  DecodedStereoFrame in;
  in.images = {small, small};
  TrackedStereoFrame frame;
  FrontendStats stats;
  CHECK_THROWS_AS(frontend.track(in, frame, stats), InputError);
}
