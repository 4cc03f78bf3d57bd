// The visualisations of pipeline/sinks/overlay_sink.h on known inputs: which pixel gets which colour.

#include <doctest/doctest.h>

#include "pipeline/sinks/overlay_sink.h"

namespace {

bool is(const voca::Rgb8& pixel, voca::Rgb8 colour) {
  return pixel.r == colour.r && pixel.g == colour.g && pixel.b == colour.b;
}

}  // namespace

TEST_CASE(
    "motion overlay: partitions, vectors, zero vectors and outliers in their colours; future references not drawn") {
  constexpr voca::Rgb8 kPartition{70, 110, 200}, kVector{40, 230, 60}, kOutlier{255, 40, 40};
  voca::GrayImage luma(32, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) luma(x, y) = 100;
  voca::MotionField field(32, 32);
  field.reset(32, 32, voca::PictureType::kP);
  REQUIRE(field.addBlock(0, 0, 16, 16, 4.f, 0.f));    // arrow (8, 8) -> (12, 8)
  REQUIRE(field.addBlock(16, 0, 16, 16, 0.f, 0.f));   // a dot at its centre (24, 8)
  REQUIRE(field.addBlock(0, 16, 16, 16, -3.f, 2.f));  // flagged below: red arrow from (8, 24)
  REQUIRE(field.addBlock(16, 16, 16, 16, 5.f, 5.f, voca::RefDirection::kFuture));
  field.finalize();
  field.blocks()[2].outlier = true;

  voca::RgbImage out;
  voca::pipeline::renderMotionOverlay(luma, field, 1.f, out);
  REQUIRE(out.width() == 32);
  REQUIRE(out.height() == 32);
  CHECK(is(out(3, 0), kPartition));                   // top edge of the first block
  CHECK(is(out(16, 5), kPartition));                  // left edge of the second
  CHECK(is(out(10, 8), kVector));                     // on the first block's arrow
  CHECK(is(out(24, 8), kVector));                     // the zero vector's dot
  CHECK(is(out(8, 24), kOutlier));                    // the outlier's arrow starts at its block's centre
  CHECK(is(out(20, 16), voca::Rgb8{100, 100, 100}));  // the future-reference block has no edge drawn
  CHECK(is(out(28, 28), voca::Rgb8{100, 100, 100}));  // nor an arrow
}
