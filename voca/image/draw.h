#pragma once
// Drawing on RGB images for the visualisations (track overlays, motion-vector plots). Everything is
// clipped to the image: parts outside are not drawn.

#include <Eigen/Core>

#include "voca/core/image.h"

namespace voca {

// The gray image as RGB (out resized to it): the canvas every visualisation draws on.
void grayToRgb(const GrayImage& gray, RgbImage& out);

// Sets one pixel if it lies inside the image.
void putPixel(RgbImage& image, int x, int y, Rgb8 colour);

// A one-pixel line from a to b (endpoints rounded to the nearest pixel, both drawn; Bresenham, so
// consecutive pixels touch and none repeats). A line longer than four times the image's width plus
// height comes from a point lost far outside and is not drawn.
void drawLine(RgbImage& image, Eigen::Vector2f a, Eigen::Vector2f b, Rgb8 colour);

// A line from `from` to `to` with a two-barbed head at `to` (no head when shorter than 1.5 px).
void drawArrow(RgbImage& image, Eigen::Vector2f from, Eigen::Vector2f to, Rgb8 colour);

// An x-shaped cross of half-size r pixels centred at p.
void drawCross(RgbImage& image, Eigen::Vector2f p, int r, Rgb8 colour);

// A circle outline of radius r pixels centred at p.
void drawCircle(RgbImage& image, Eigen::Vector2f p, float r, Rgb8 colour);

}  // namespace voca
