#include "pipeline/sinks/overlay_sink.h"

#include <algorithm>
#include <cmath>

#include "voca/image/draw.h"

namespace voca::pipeline {

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
