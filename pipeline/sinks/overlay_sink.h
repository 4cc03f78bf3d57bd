#pragma once
// The visualisations: a video of the left camera with each point's temporal step drawn (the paper's
// Fig. 1): blue dot = previous position, yellow cross and line = motion-vector prior, green circle
// and line = converged position (red when rejected), cyan = new detection; and a frame with what the
// codec saw (the paper's Fig. 3, `voca mv`).

#include <filesystem>
#include <memory>

#include "drivers/encode/rgb_video_writer.h"
#include "pipeline/sinks/sink_stage.h"
#include "voca/core/image.h"
#include "voca/motion/motion_field.h"

namespace voca::pipeline {

// Draws the overlay of one frame into out (resized to the image).
void renderTrackOverlay(const GrayImage& left, std::span<const PointTrace> traces,
                        std::span<const KeypointObservation> observations, RgbImage& out);

// Draws a decoded frame with its block partitions (blue), its past-reference vectors as arrows scaled
// by arrow_scale (green, a dot for a zero vector) and the vectors flagged as outliers (red, on top).
void renderMotionOverlay(const GrayImage& luma, const MotionField& field, float arrow_scale, RgbImage& out);

class OverlaySink final : public FrameSink {
 public:
  OverlaySink(const std::filesystem::path& file, int fps, int width, int height);
  void consume(const FrameSlot& slot) override;
  void finish() override;

 private:
  encode::RgbVideoWriter writer_;
  RgbImage image_;
};

}  // namespace voca::pipeline
