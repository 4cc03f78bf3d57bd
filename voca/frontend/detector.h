#pragma once
// Grid-based corner detection with a FAST-style segment test (our own; no OpenCV): at most one new
// corner per empty grid cell, the strongest one, with the threshold halved until one is found.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "voca/core/image.h"

namespace voca {

struct DetectorParams {
  int grid_size_px = 40;
  int max_threshold = 40;  // first segment-test threshold (gray levels); halved down to min_threshold
  int min_threshold = 5;
  int border_px = 19;  // corners closer than this to the image border are not taken
  // Only corners within this distance of safe_center are taken (fisheye rims); 0 = no mask.
  float safe_radius_px = 0.f;
  Eigen::Vector2f safe_center = Eigen::Vector2f::Zero();
};

// Segment test on the 16-pixel Bresenham circle of radius 3: a corner has 9 contiguous circle pixels
// all brighter than centre + threshold or all darker than centre - threshold. Returns the response
// (sum of the excess over the threshold along the circle in the winning direction), 0 = no corner.
// (x, y) must be at least 3 pixels inside the image.
int cornerResponse(GrayView image, int x, int y, int threshold);

// The grid cells of a width x height image that can hold a corner: those with pixels at least
// border_px (and 3) from every edge. detect() adds at most one new corner per cell and frame.
int detectionCells(int width, int height, int grid_size_px, int border_px);

// Fills empty grid cells of an image with corners. Cell (i, j) covers pixels [i g, (i+1) g) x
// [j g, (j+1) g); a cell is empty when no existing point rounds into it. Buffers are sized for the
// largest image at construction; detect() does not allocate.
class GridDetector {
 public:
  GridDetector() = default;
  GridDetector(int max_width, int max_height, int grid_size_px);

  // Appends at most max_new corners (pixel coordinates) to `out`; returns how many were added.
  // `out` must have capacity for them (reserve once) so that appending does not allocate.
  // `blocked`, when not empty, holds one byte per cell (row-major, cellsX() x cellsY() of the image):
  // non-zero cells get no corner.
  int detect(GrayView image, std::span<const Eigen::Vector2f> existing, const DetectorParams& params, int max_new,
             std::vector<Eigen::Vector2f>& out, std::span<const std::uint8_t> blocked = {});
  int gridSize() const { return grid_size_px_; }

 private:
  int grid_size_px_ = 0;
  // A corner of one cell at the lowest threshold; it passes the segment test at every threshold t
  // with t < max(bright, dark) (the arc strengths, see detector.cpp).
  struct Candidate {
    int x = 0;
    int y = 0;
    std::uint8_t bright = 0;
    std::uint8_t dark = 0;
  };
  std::vector<std::uint8_t> occupied_;
  std::vector<std::uint8_t> row_buffers_;  // arc strengths (bright, dark) of one row of a cell
  std::vector<Candidate> candidates_;
};

}  // namespace voca
