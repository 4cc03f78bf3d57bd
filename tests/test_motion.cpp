// MotionField: O(1) lookup correctness, "no vector" cases, fixed capacity, I-frame bridging and
// median-threshold outlier flags.

#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "voca/motion/motion_field.h"

using voca::MotionBlock;
using voca::MotionField;
using voca::PictureType;
using voca::RefDirection;

namespace {

struct Rect {
  int x, y, w, h;
};

// Tiles the image with macroblock-like partitions (16x16, 16x8, 8x16, 8x8 and a few intra holes)
// and returns, per pixel, the index of the block that covers it (-1 for holes).
std::vector<int> tileRandom(MotionField& field, int width, int height, std::mt19937& rng) {
  std::vector<int> owner(static_cast<std::size_t>(width * height), -1);
  std::uniform_int_distribution<int> kind(0, 4);
  std::uniform_real_distribution<float> mv(-20.f, 20.f);
  auto add = [&](Rect r) {
    const int before = static_cast<int>(field.blocks().size());
    if (!field.addBlock(r.x, r.y, r.w, r.h, mv(rng), mv(rng))) return;
    for (int y = std::max(0, r.y); y < std::min(height, r.y + r.h); ++y)
      for (int x = std::max(0, r.x); x < std::min(width, r.x + r.w); ++x)
        owner[static_cast<std::size_t>(y * width + x)] = before;
  };
  for (int my = 0; my < height; my += 16) {
    for (int mx = 0; mx < width; mx += 16) {
      switch (kind(rng)) {
        case 0:
          add({mx, my, 16, 16});
          break;
        case 1:
          add({mx, my, 16, 8});
          add({mx, my + 8, 16, 8});
          break;
        case 2:
          add({mx, my, 8, 16});
          add({mx + 8, my, 8, 16});
          break;
        case 3:
          for (int i = 0; i < 4; ++i) add({mx + 8 * (i & 1), my + 8 * (i >> 1), 8, 8});
          break;
        default:
          break;  // intra macroblock: no vector
      }
    }
  }
  field.finalize();
  return owner;
}

}  // namespace

TEST_CASE("every pixel maps to the block covering it, uncovered pixels to none") {
  std::mt19937 rng(7);
  // 200x120 is not a multiple of 16 (macroblocks overhang the right/bottom edge, as in a codec's
  // padded picture) to exercise clipping.
  const int width = 200, height = 120;
  MotionField field(256, 128);
  field.reset(width, height, PictureType::kP);
  const std::vector<int> owner = tileRandom(field, width, height, rng);
  REQUIRE(field.hasVectors());
  int mismatches = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const MotionBlock* block = field.blockAt(x, y);
      const int expected = owner[static_cast<std::size_t>(y * width + x)];
      const int got = block == nullptr ? -1 : static_cast<int>(block - field.blocks().data());
      mismatches += expected != got ? 1 : 0;
    }
  }
  CHECK(mismatches == 0);
  // Outside the image there is no vector.
  CHECK(field.blockAt(-1, 0) == nullptr);
  CHECK(field.blockAt(width, 0) == nullptr);
  CHECK(field.blockAt(0, height) == nullptr);
  // Pixel (0, y) spans x in [-0.5, 0.5): just left of that is outside.
  CHECK_FALSE(field.forwardFlowAt(-0.51f, 3.f).has_value());
  CHECK(field.forwardFlowAt(-0.5f, 3.f).has_value() == (field.blockAt(0, 3) != nullptr));
  // Far outside and NaN: no vector (and no undefined float-to-int conversion).
  CHECK_FALSE(field.forwardFlowAt(1e10f, 3.f).has_value());
  CHECK_FALSE(field.forwardFlowAt(3.f, -1e10f).has_value());
  CHECK_FALSE(field.forwardFlowAt(std::nanf(""), 3.f).has_value());
}

TEST_CASE("forward flow is the stored displacement of the block at a sub-pixel position") {
  MotionField field(64, 64);
  field.reset(64, 64, PictureType::kP);
  REQUIRE(field.addBlock(16, 16, 16, 16, 1.25f, -0.5f));
  field.finalize();
  // Pixel-centre coordinates: the block's pixels 16..31 span [15.5, 31.5).
  const auto flow = field.forwardFlowAt(31.49f, 16.0f);
  REQUIRE(flow.has_value());
  CHECK((*flow)(0) == 1.25f);  // stored and returned unchanged
  CHECK((*flow)(1) == -0.5f);
  CHECK(field.forwardFlowAt(15.5f, 20.0f).has_value());
  CHECK_FALSE(field.forwardFlowAt(31.5f, 16.0f).has_value());
  CHECK_FALSE(field.forwardFlowAt(15.49f, 20.0f).has_value());
  CHECK_FALSE(field.forwardFlowAt(20.0f, 31.5f).has_value());
  // The block centre in the same convention.
  CHECK(field.blocks()[0].centreX() == 23.5f);
  CHECK(field.blocks()[0].centreY() == 23.5f);
}

TEST_CASE("past-reference vectors win over future-reference ones in the lookup") {
  MotionField field(32, 32);
  field.reset(32, 32, PictureType::kB);
  REQUIRE(field.addBlock(0, 0, 16, 16, 1.f, 0.f, RefDirection::kPast));
  REQUIRE(field.addBlock(0, 0, 16, 16, 5.f, 0.f, RefDirection::kFuture));
  REQUIRE(field.addBlock(16, 0, 16, 16, 7.f, 0.f, RefDirection::kFuture));
  field.finalize();
  CHECK(field.blockAt(3, 3)->ref == RefDirection::kPast);
  CHECK(field.blockAt(20, 3)->ref == RefDirection::kFuture);
}

TEST_CASE("I-frames and reset fields have no vectors; capacity is fixed") {
  MotionField field(64, 48);
  const std::size_t capacity = field.blockCapacity();
  field.reset(64, 48, PictureType::kI);
  field.finalize();
  CHECK_FALSE(field.hasVectors());
  for (int y = 0; y < 48; y += 3)
    for (int x = 0; x < 64; x += 3) CHECK(field.blockAt(x, y) == nullptr);
  CHECK_THROWS_AS(field.reset(65, 48, PictureType::kP), std::length_error);
  // Fill beyond capacity: extra blocks are refused, storage is never reallocated.
  field.reset(64, 48, PictureType::kP);
  const MotionBlock* storage = field.blocks().data();
  std::size_t accepted = 0;
  for (int i = 0; i < 10000; ++i)
    accepted += field.addBlock((i * 4) % 64, (i * 4 / 64 * 4) % 48, 4, 4, 0.f, 0.f) ? 1 : 0;
  CHECK(accepted == capacity);
  CHECK(field.blockCapacity() == capacity);
  CHECK(field.blocks().data() == storage);
  // A block entirely outside the image is refused.
  field.reset(64, 48, PictureType::kP);
  CHECK_FALSE(field.addBlock(64, 0, 16, 16, 0.f, 0.f));
}

TEST_CASE("macroblock quantisers: looked up by position, given to the blocks, cleared by reset, copied") {
  // 60x40: the last macroblock column and row are cut by the image edge, as in 1241x376 KITTI.
  MotionField field(64, 48);
  field.reset(60, 40, PictureType::kP);
  CHECK_FALSE(field.hasQp());
  CHECK(field.qpAt(0, 0) == MotionField::kNoQp);
  // Macroblock (mx, my) gets QP 10 + 4 * my + mx; (3, 2) is left out: no quantiser exported there.
  for (int my = 0; my < 3; ++my)
    for (int mx = 0; mx < 4; ++mx)
      if (mx != 3 || my != 2) CHECK(field.setQp(16 * mx, 16 * my, 16, 16, 10 + 4 * my + mx));
  CHECK_FALSE(field.setQp(0, 0, 16, 16, -1));
  CHECK_FALSE(field.setQp(0, 0, 16, 16, 40000));
  REQUIRE(field.addBlock(16, 0, 8, 16, 1.f, 0.f));    // left half of macroblock (1, 0)
  REQUIRE(field.addBlock(56, 16, 8, 8, 0.f, 1.f));    // clipped to 4x8 by the right edge, in (3, 1)
  REQUIRE(field.addBlock(48, 32, 16, 16, 0.f, 0.f));  // in (3, 2), which has no quantiser
  field.finalize();
  REQUIRE(field.hasQp());
  int wrong = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 60; ++x) {
      const int mx = x / 16, my = y / 16;
      wrong += field.qpAt(x, y) != (mx == 3 && my == 2 ? MotionField::kNoQp : 10 + 4 * my + mx);
    }
  CHECK(wrong == 0);
  CHECK(field.qpAt(60, 0) == MotionField::kNoQp);
  CHECK(field.qpAt(0, -1) == MotionField::kNoQp);
  CHECK(field.blocks()[0].qp == 11);
  CHECK(field.blocks()[1].qp == 17);
  CHECK(field.blocks()[2].qp == MotionField::kNoQp);

  MotionField copy(64, 48);
  copy.copyFrom(field);
  CHECK(copy.qpAt(20, 20) == 15);
  CHECK(copy.blocks()[0].qp == 11);

  // The next frame starts without quantisers, and a frame that sets one clears the rest.
  field.reset(60, 40, PictureType::kP);
  field.finalize();
  CHECK_FALSE(field.hasQp());
  CHECK(field.qpAt(20, 20) == MotionField::kNoQp);
  field.reset(60, 40, PictureType::kP);
  field.setQp(0, 0, 16, 16, 30);
  field.finalize();
  CHECK(field.qpAt(5, 5) == 30);
  CHECK(field.qpAt(20, 20) == MotionField::kNoQp);
}

TEST_CASE("copies keep the full capacity, so a copied field still takes a whole frame") {
  MotionField field(64, 48);
  field.reset(64, 48, PictureType::kP);
  REQUIRE(field.addBlock(0, 0, 16, 16, 1.f, 2.f));
  field.finalize();
  const auto checkCopy = [&](MotionField& copy) {
    CHECK(copy.blockCapacity() == field.blockCapacity());
    REQUIRE(copy.blocks().size() == 1);
    REQUIRE(copy.blockAt(15, 15) != nullptr);
    CHECK(copy.blockAt(15, 15)->dy == 2.f);
    CHECK(copy.blockAt(16, 15) == nullptr);
    // A later frame with the smallest partitions everywhere must fit.
    copy.reset(64, 48, PictureType::kP);
    std::size_t accepted = 0;
    for (int y = 0; y < 48; y += 4)
      for (int x = 0; x < 64; x += 4) accepted += copy.addBlock(x, y, 4, 4, 0.f, 0.f) ? 1 : 0;
    CHECK(accepted == 16u * 12u);
  };
  MotionField constructed(field);
  checkCopy(constructed);
  MotionField assigned;
  assigned = field;
  checkCopy(assigned);
  MotionField smaller(16, 16);
  smaller = field;
  checkCopy(smaller);
}

TEST_CASE("I-frame bridging: the last field with vectors carries over I-frames, never across a gap") {
  voca::MotionPriorBridge bridge(64, 64);
  MotionField p(64, 64), i_frame(64, 64), b_frame(64, 64);
  const auto makeInter = [](MotionField& field, PictureType type, float dx) {
    field.reset(64, 64, type);
    field.addBlock(0, 0, 16, 16, dx, 3.f);
    field.finalize();
  };
  i_frame.reset(64, 64, PictureType::kI);
  i_frame.finalize();
  bool bridged = false;

  // Nothing to bridge from yet.
  CHECK(bridge.prior(i_frame, 0, bridged) == nullptr);
  CHECK_FALSE(bridged);

  // A P-frame's own vectors are its prior (not a copy).
  makeInter(p, PictureType::kP, 2.f);
  CHECK(bridge.prior(p, 0, bridged) == &p);
  CHECK_FALSE(bridged);

  // The I-frame gets the remembered copy, flagged; the copy outlives the P-frame's buffer, which
  // the decoder reuses.
  const MotionField* carried = nullptr;
  {
    voca::MotionPriorBridge fresh(64, 64);
    makeInter(p, PictureType::kP, 2.f);
    REQUIRE(fresh.prior(p, 0, bridged) == &p);
    p.reset(64, 64, PictureType::kP);  // overwritten by the next decode
    carried = fresh.prior(i_frame, 0, bridged);
    REQUIRE(carried != nullptr);
    CHECK(carried != &i_frame);
    CHECK(bridged);
    REQUIRE(carried->blockAt(8, 8) != nullptr);
    CHECK(carried->blockAt(8, 8)->dx == 2.f);
    CHECK(carried->blockAt(20, 8) == nullptr);
  }

  // The tracker's rules: any field with vectors is remembered (a B-frame too) ...
  bridged = false;
  makeInter(b_frame, PictureType::kB, 5.f);
  CHECK(bridge.prior(b_frame, 0, bridged) == &b_frame);
  carried = bridge.prior(i_frame, 0, bridged);
  REQUIRE(carried != nullptr);
  CHECK(bridged);
  CHECK(carried->blockAt(8, 8)->dx == 5.f);

  // ... only an I-frame is bridged (an inter picture without vectors has no prior) ...
  MotionField empty_p(64, 64);
  empty_p.reset(64, 64, PictureType::kP);
  empty_p.finalize();
  bridged = false;
  CHECK(bridge.prior(empty_p, 0, bridged) == nullptr);
  CHECK_FALSE(bridged);

  // ... and after a gap there is no prior at all, although the vectors are still remembered.
  makeInter(p, PictureType::kP, 9.f);
  CHECK(bridge.prior(p, 1, bridged) == nullptr);
  CHECK(bridge.prior(i_frame, 2, bridged) == nullptr);
  CHECK_FALSE(bridged);
  carried = bridge.prior(i_frame, 0, bridged);
  REQUIRE(carried != nullptr);
  CHECK(carried->blockAt(8, 8)->dx == 9.f);

  // clear() forgets; a disabled bridge passes a frame's own vectors and never carries.
  bridge.clear();
  bridged = false;
  CHECK(bridge.prior(i_frame, 0, bridged) == nullptr);
  voca::MotionPriorBridge disabled(64, 64, false);
  CHECK(disabled.prior(p, 0, bridged) == &p);
  CHECK(disabled.prior(i_frame, 0, bridged) == nullptr);
  CHECK_FALSE(bridged);
}

TEST_CASE("median thresholding flags vectors that deviate from their neighbourhood") {
  // A smooth field (a slow zoom: flow grows linearly from the centre) with three planted outliers.
  const int width = 160, height = 128;
  MotionField field(width, height);
  field.reset(width, height, PictureType::kP);
  std::vector<std::size_t> planted;
  for (int y = 0; y < height; y += 16) {
    for (int x = 0; x < width; x += 16) {
      float dx = 0.02f * (x + 8 - width / 2), dy = 0.02f * (y + 8 - height / 2);
      const bool outlier = (x == 32 && y == 32) || (x == 128 && y == 96) || (x == 0 && y == 0);
      if (outlier) {
        planted.push_back(field.blocks().size());
        dx += 9.f;
        dy -= 6.f;
      }
      field.addBlock(x, y, 16, 16, dx, dy);
    }
  }
  field.finalize();
  const int flagged = field.flagOutliers({});
  // The zoom changes the flow by 0.32 px per block, far below the 2 px threshold, so exactly the
  // planted blocks (9 and 6 px off) are flagged.
  CHECK(flagged == 3);
  for (std::size_t index : planted) CHECK(field.blocks()[index].outlier);
}
