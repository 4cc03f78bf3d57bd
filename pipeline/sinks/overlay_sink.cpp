#include "pipeline/sinks/overlay_sink.h"

#include <algorithm>
#include <cmath>

namespace voca::pipeline {

namespace {

void putPixel(RgbImage& image, int x, int y, Rgb8 colour) {
  if (x >= 0 && y >= 0 && x < image.width() && y < image.height()) image(x, y) = colour;
}

void drawLine(RgbImage& image, Eigen::Vector2f a, Eigen::Vector2f b, Rgb8 colour) {
  const float length = (b - a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(length)));
  if (steps > 4 * (image.width() + image.height())) return;  // a lost point far outside: not worth drawing
  for (int i = 0; i <= steps; ++i) {
    const Eigen::Vector2f p = a + (b - a) * (static_cast<float>(i) / static_cast<float>(steps));
    putPixel(image, static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())), colour);
  }
}

void drawCross(RgbImage& image, Eigen::Vector2f p, int r, Rgb8 colour) {
  const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
  for (int d = -r; d <= r; ++d) {
    putPixel(image, x + d, y + d, colour);
    putPixel(image, x + d, y - d, colour);
  }
}

void drawCircle(RgbImage& image, Eigen::Vector2f p, float r, Rgb8 colour) {
  const int n = static_cast<int>(std::ceil(2.f * 3.14159f * r));
  for (int i = 0; i < n; ++i) {
    const float a = 2.f * 3.14159265f * static_cast<float>(i) / static_cast<float>(n);
    putPixel(image, static_cast<int>(std::lround(p.x() + r * std::cos(a))),
             static_cast<int>(std::lround(p.y() + r * std::sin(a))), colour);
  }
}

}  // namespace

void renderTrackOverlay(const GrayImage& left, std::span<const PointTrace> traces,
                        std::span<const KeypointObservation> observations, RgbImage& out) {
  out.resize(left.width(), left.height());
  for (int y = 0; y < left.height(); ++y) {
    for (int x = 0; x < left.width(); ++x) {
      const std::uint8_t v = left(x, y);
      out(x, y) = {v, v, v};
    }
  }
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

OverlaySink::OverlaySink(const std::filesystem::path& file, int fps, int width, int height) : writer_(file, fps, 1) {
  image_.reserve(width, height);
}

void OverlaySink::consume(const FrameSlot& slot) {
  renderTrackOverlay(slot.frame.images[0], slot.left_traces, slot.tracked.observations[0], image_);
  writer_.write(image_.view());
}

void OverlaySink::finish() { writer_.finish(); }

}  // namespace voca::pipeline
