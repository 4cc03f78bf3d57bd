#include "pipeline/sinks/overlay_sink.h"

#include <algorithm>
#include <cmath>

#include "voca/image/draw.h"

namespace voca::pipeline {

void renderTrackOverlay(const GrayImage& left, std::span<const PointTrace> traces,
                        std::span<const KeypointObservation> observations, RgbImage& out) {
  grayToRgb(left, out);
  const Rgb8 blue{60, 140, 255}, yellow{255, 220, 0}, green{0, 230, 60}, red{255, 40, 40}, cyan{0, 220, 220};
  for (const PointTrace& t : traces) {
    if (t.has_prior) {
      drawLine(out, t.previous_px, t.prior_px, yellow);
      drawCross(out, t.prior_px, 2, yellow);
    }
    drawLine(out, t.previous_px, t.tracked_px, t.kept ? green : red);
    drawCircle(out, t.tracked_px, 3.f, t.kept ? green : red);
    putPixel(out, static_cast<int>(std::lround(t.previous_px.x())), static_cast<int>(std::lround(t.previous_px.y())),
             blue);
    drawCircle(out, t.previous_px, 1.f, blue);
  }
  // Points new in this frame have no trace yet.
  for (const KeypointObservation& o : observations) {
    const bool traced =
        std::any_of(traces.begin(), traces.end(), [&](const PointTrace& t) { return t.track_id == o.track_id; });
    if (!traced) drawCircle(out, o.px, 4.f, cyan);
  }
}

void renderMotionOverlay(const GrayImage& luma, const MotionField& field, float arrow_scale, RgbImage& out) {
  constexpr Rgb8 kPartitionColour{70, 110, 200};
  constexpr Rgb8 kVectorColour{40, 230, 60};
  constexpr Rgb8 kOutlierColour{255, 40, 40};
  grayToRgb(luma, out);
  // Partitions first (top and left edge of every block, so shared edges are drawn once), then the
  // vectors on top; outliers last so they stay visible.
  for (const MotionBlock& b : field.blocks()) {
    if (b.ref != RefDirection::kPast) continue;
    for (int x = b.x; x < b.x + b.w; ++x) putPixel(out, x, b.y, kPartitionColour);
    for (int y = b.y; y < b.y + b.h; ++y) putPixel(out, b.x, y, kPartitionColour);
  }
  for (const bool outliers : {false, true}) {
    for (const MotionBlock& b : field.blocks()) {
      if (b.ref != RefDirection::kPast || b.outlier != outliers) continue;
      const float cx = b.centreX(), cy = b.centreY();
      const Rgb8 colour = outliers ? kOutlierColour : kVectorColour;
      if (b.dx == 0.f && b.dy == 0.f) {
        putPixel(out, static_cast<int>(std::lround(cx)), static_cast<int>(std::lround(cy)), colour);
      } else {
        drawArrow(out, {cx, cy}, {cx + arrow_scale * b.dx, cy + arrow_scale * b.dy}, colour);
      }
    }
  }
}

OverlaySink::OverlaySink(const std::filesystem::path& file, int fps, int width, int height) : writer_(file, fps, 1) {
  image_.reserve(width, height);
}

void OverlaySink::consume(const FrameSlot& slot) {
  renderTrackOverlay(slot.frame.images[0], slot.left_traces, slot.tracked.observations[0], image_);
  writer_.write(image_.view());
}

void OverlaySink::finish() { writer_.finish(); }

}  // namespace voca::pipeline
