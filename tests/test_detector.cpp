// The grid detector against a plain reference: the segment test written out pixel by pixel, every
// threshold of the halving sequence scanned over the whole cell. The detector computes the same
// thing with a vectorised pre-test and one strength per pixel; these tests require exactly the same
// corners (same cells, same pixels, same order), so any shortcut that changes the output fails.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

#include "voca/frontend/detector.h"

using namespace voca;

namespace {

// Bresenham circle of radius 3, clockwise from the top, as in Rosten's FAST.
constexpr int kCircleX[16] = {0, 1, 2, 3, 3, 3, 2, 1, 0, -1, -2, -3, -3, -3, -2, -1};
constexpr int kCircleY[16] = {-3, -3, -2, -1, 0, 1, 2, 3, 3, 3, 2, 1, 0, -1, -2, -3};

// Segment test by definition: for each direction, the circle pixels beyond the threshold; a corner
// needs 9 of them contiguous (circularly); the response is their total excess over the threshold.
int referenceResponse(GrayView image, int x, int y, int threshold) {
  const int c = image(x, y);
  int response = 0;
  for (int sign : {1, -1}) {
    bool beyond[16];
    int excess = 0;
    for (int k = 0; k < 16; ++k) {
      const int d = sign * (image(x + kCircleX[k], y + kCircleY[k]) - c);
      beyond[k] = d > threshold;
      if (beyond[k]) excess += d - threshold;
    }
    bool arc = false;
    for (int start = 0; start < 16 && !arc; ++start) {
      bool all = true;
      for (int j = 0; j < 9; ++j) all = all && beyond[(start + j) % 16];
      arc = all;
    }
    if (arc) response = std::max(response, excess);
  }
  return response;
}

// The documented behaviour of GridDetector::detect, written as directly as possible.
std::vector<Eigen::Vector2f> referenceDetect(GrayView image, const std::vector<Eigen::Vector2f>& existing,
                                             const DetectorParams& params, int grid, int max_new) {
  const int cells_x = (image.width + grid - 1) / grid, cells_y = (image.height + grid - 1) / grid;
  std::vector<bool> occupied(static_cast<std::size_t>(cells_x * cells_y), false);
  for (const Eigen::Vector2f& p : existing) {
    const int cx = static_cast<int>(std::floor((p.x() + 0.5f) / static_cast<float>(grid)));
    const int cy = static_cast<int>(std::floor((p.y() + 0.5f) / static_cast<float>(grid)));
    if (cx >= 0 && cy >= 0 && cx < cells_x && cy < cells_y)
      occupied[static_cast<std::size_t>(cy * cells_x + cx)] = true;
  }
  const int border = std::max(params.border_px, 3);
  const float radius2 = params.safe_radius_px * params.safe_radius_px;
  std::vector<Eigen::Vector2f> found;
  for (int cy = 0; cy < cells_y; ++cy) {
    for (int cx = 0; cx < cells_x; ++cx) {
      if (occupied[static_cast<std::size_t>(cy * cells_x + cx)]) continue;
      if (static_cast<int>(found.size()) >= max_new) return found;
      for (int t = params.max_threshold; t >= params.min_threshold; t /= 2) {
        int best = 0, best_x = 0, best_y = 0;
        for (int y = std::max(cy * grid, border); y < std::min((cy + 1) * grid, image.height - border); ++y) {
          for (int x = std::max(cx * grid, border); x < std::min((cx + 1) * grid, image.width - border); ++x) {
            if (radius2 > 0.f) {
              const float dx = static_cast<float>(x) - params.safe_center.x();
              const float dy = static_cast<float>(y) - params.safe_center.y();
              if (dx * dx + dy * dy > radius2) continue;
            }
            const int r = referenceResponse(image, x, y, t);
            if (r > best) {
              best = r;
              best_x = x;
              best_y = y;
            }
          }
        }
        if (best > 0) {
          found.emplace_back(static_cast<float>(best_x), static_cast<float>(best_y));
          break;
        }
        if (t == 0) break;
      }
    }
  }
  return found;
}

// Runs the detector (output vector reserved, as the frontend does) and the reference; both must agree.
void expectSameAsReference(GrayView image, const std::vector<Eigen::Vector2f>& existing, const DetectorParams& params,
                           int grid, int max_new) {
  GridDetector detector(image.width, image.height, grid);
  std::vector<Eigen::Vector2f> found;
  found.reserve(static_cast<std::size_t>(std::max(max_new, 0)));
  const int added = detector.detect(image, existing, params, max_new, found);
  const std::vector<Eigen::Vector2f> expected = referenceDetect(image, existing, params, grid, max_new);
  INFO("image " << image.width << "x" << image.height << " grid " << grid << " thresholds " << params.max_threshold
                << ".." << params.min_threshold << " border " << params.border_px << " radius " << params.safe_radius_px
                << " existing " << existing.size() << " max_new " << max_new);
  CHECK(added == static_cast<int>(found.size()));
  REQUIRE(found.size() == expected.size());
  for (std::size_t i = 0; i < found.size(); ++i) {
    INFO("corner " << i);
    CHECK(found[i].x() == expected[i].x());
    CHECK(found[i].y() == expected[i].y());
  }
}

// Blocks of random grey on a random background plus noise: many corners of all strengths.
GrayImage blockImage(int w, int h, std::mt19937& rng, int noise) {
  std::uniform_int_distribution<int> grey(0, 255), pos_x(-10, w), pos_y(-10, h), size(3, 30), jitter(-noise, noise);
  GrayImage image(w, h, static_cast<std::uint8_t>(grey(rng)));
  for (int b = 0; b < 25; ++b) {
    const int x0 = pos_x(rng), y0 = pos_y(rng), sx = size(rng), sy = size(rng);
    const auto value = static_cast<std::uint8_t>(grey(rng));
    for (int y = std::max(y0, 0); y < std::min(y0 + sy, h); ++y)
      for (int x = std::max(x0, 0); x < std::min(x0 + sx, w); ++x) image(x, y) = value;
  }
  if (noise > 0) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        image(x, y) = static_cast<std::uint8_t>(std::clamp(image(x, y) + jitter(rng), 0, 255));
  }
  return image;
}

}  // namespace

TEST_CASE("detector: cornerResponse is the segment test by definition at every threshold") {
  std::mt19937 rng(7);
  const GrayImage image = blockImage(64, 48, rng, 6);
  int corners = 0;
  for (int t : {0, 1, 3, 5, 10, 20, 40, 100, 254, 255}) {
    for (int y = 3; y < 45; ++y) {
      for (int x = 3; x < 61; ++x) {
        const int r = cornerResponse(image.view(), x, y, t);
        REQUIRE(r == referenceResponse(image.view(), x, y, t));
        corners += r > 0;
      }
    }
  }
  CHECK(corners > 100);  // the comparison saw corners, not only zeros
}

TEST_CASE("detector: same corners as the reference on uniform noise") {
  // Noise has corners of every strength everywhere, so each cell ends at a different threshold.
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> grey(0, 255);
  for (const auto& [w, h] : {std::pair{160, 120}, std::pair{157, 113}, std::pair{41, 39}}) {
    GrayImage image(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) image(x, y) = static_cast<std::uint8_t>(grey(rng));
    for (int grid : {40, 23, 16}) expectSameAsReference(image.view(), {}, DetectorParams{}, grid, 1000);
  }
}

TEST_CASE("detector: same corners as the reference on structured images, random parameters") {
  // Blocks with noise of several amplitudes (from flat blocks whose corners are found at the first
  // threshold to weak ones only found at the lowest), saturated greys (0 and 255 test the clamped
  // bounds), odd sizes (partial cells at the right and bottom edges), borders from 0 to 25, safe
  // radius masks, existing points (some outside the image) and max_new limits.
  std::mt19937 rng(2024);
  std::uniform_int_distribution<int> coin(0, 1), noise(0, 12), border(0, 25), grid_pick(0, 3), max_pick(1, 60),
      min_pick(0, 12);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  int total_corners = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 60 + static_cast<int>(unit(rng) * 140.f), h = 50 + static_cast<int>(unit(rng) * 100.f);
    const GrayImage image = blockImage(w, h, rng, noise(rng));
    DetectorParams params;
    params.border_px = border(rng);
    params.max_threshold = max_pick(rng);
    params.min_threshold = std::min(min_pick(rng), params.max_threshold);
    if (coin(rng) != 0) {
      params.safe_radius_px = 10.f + unit(rng) * static_cast<float>(w);
      params.safe_center = Eigen::Vector2f(unit(rng) * static_cast<float>(w), unit(rng) * static_cast<float>(h));
    }
    const int grid = std::array{40, 32, 17, 9}[static_cast<std::size_t>(grid_pick(rng))];
    std::vector<Eigen::Vector2f> existing;
    const int num_existing = coin(rng) != 0 ? static_cast<int>(unit(rng) * 30.f) : 0;
    for (int i = 0; i < num_existing; ++i) {
      existing.emplace_back(unit(rng) * static_cast<float>(w + 20) - 10.f,
                            unit(rng) * static_cast<float>(h + 20) - 10.f);
    }
    const int max_new = coin(rng) != 0 ? 1000 : static_cast<int>(unit(rng) * 10.f);
    expectSameAsReference(image.view(), existing, params, grid, max_new);
    total_corners += static_cast<int>(referenceDetect(image.view(), existing, params, grid, max_new).size());
  }
  CHECK(total_corners > 200);  // the trials found corners to compare, not only empty cells
}

TEST_CASE("detector: a strided view (crop of a larger image) gives the crop's corners") {
  // The circle offsets depend on the stride: a crop must behave like a copy of the same pixels.
  std::mt19937 rng(5);
  const GrayImage big = blockImage(200, 150, rng, 4);
  const GrayView crop{&big(30, 20), 130, 100, big.stride()};
  GrayImage copy(130, 100);
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 130; ++x) copy(x, y) = crop(x, y);
  GridDetector detector(130, 100, 40);
  std::vector<Eigen::Vector2f> from_crop, from_copy;
  from_crop.reserve(50);
  from_copy.reserve(50);
  DetectorParams params;
  params.border_px = 4;
  detector.detect(crop, {}, params, 50, from_crop);
  detector.detect(copy.view(), {}, params, 50, from_copy);
  CHECK(from_crop.size() >= 4);
  CHECK(from_crop == from_copy);
  expectSameAsReference(crop, {}, params, 40, 50);
}

TEST_CASE("detector: thresholds at the ends of the 8-bit range") {
  // A sequence that ends at 255 or above can find nothing (no difference exceeds 255); threshold 0
  // counts any difference; a black square on white is a corner up to threshold 254.
  GrayImage image(80, 80, 255);
  for (int y = 30; y < 80; ++y)
    for (int x = 30; x < 80; ++x) image(x, y) = 0;
  DetectorParams params;
  params.border_px = 5;
  for (const auto& [max_t, min_t] : {std::pair{255, 255}, std::pair{300, 255}, std::pair{254, 254}, std::pair{1, 0},
                                     std::pair{0, 0}, std::pair{3, -4}}) {
    params.max_threshold = max_t;
    params.min_threshold = min_t;
    expectSameAsReference(image.view(), {}, params, 40, 100);
  }
  params.max_threshold = params.min_threshold = 254;
  GridDetector detector(80, 80, 40);
  std::vector<Eigen::Vector2f> found;
  found.reserve(4);
  detector.detect(image.view(), {}, params, 4, found);
  CHECK(found.size() == 1);
}

TEST_CASE("detector: blocked cells get no corner; the others the same as without the mask") {
  // Blocking a cell must act exactly like an existing point in it (the frontend's right-only
  // detection blocks the cells the left camera sees).
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> grey(0, 255);
  const int w = 160, h = 120, grid = 40, cells_x = 4, cells_y = 3;
  GrayImage image(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) image(x, y) = static_cast<std::uint8_t>(grey(rng));
  std::vector<std::uint8_t> blocked(cells_x * cells_y, 0);
  std::vector<Eigen::Vector2f> existing;
  for (int cell : {0, 5, 6, 11}) {
    blocked[static_cast<std::size_t>(cell)] = 1;
    existing.emplace_back(static_cast<float>((cell % cells_x) * grid + 20),
                          static_cast<float>((cell / cells_x) * grid + 20));
  }
  GridDetector detector(w, h, grid);
  std::vector<Eigen::Vector2f> with_mask, with_points;
  with_mask.reserve(64);
  with_points.reserve(64);
  const int added = detector.detect(image.view(), {}, DetectorParams{}, 64, with_mask, blocked);
  detector.detect(image.view(), existing, DetectorParams{}, 64, with_points);
  CHECK(added == 8);  // noise has corners in every free cell
  REQUIRE(with_mask.size() == with_points.size());
  for (std::size_t i = 0; i < with_mask.size(); ++i) {
    CHECK(with_mask[i] == with_points[i]);
    const int cell = static_cast<int>(with_mask[i].y()) / grid * cells_x + static_cast<int>(with_mask[i].x()) / grid;
    CHECK(blocked[static_cast<std::size_t>(cell)] == 0);
  }
  // A mask for another grid is an error, not a silent misreading.
  const std::vector<std::uint8_t> wrong(5, 0);
  CHECK_THROWS_AS(detector.detect(image.view(), {}, DetectorParams{}, 64, with_mask, wrong), std::invalid_argument);
}

TEST_CASE("detector: detectionCells counts the cells detect() can fill, known answers and on noise") {
  CHECK(detectionCells(752, 480, 40, 19) == 19 * 12);  // EuRoC: every cell reaches inside the border
  CHECK(detectionCells(96, 64, 40, 19) == 2 * 2);
  CHECK(detectionCells(752, 480, 40, 300) == 0);  // the border leaves no row
  CHECK(detectionCells(8, 8, 4, 0) == 2 * 2);     // a border below 3 px counts as 3, as in detect()
  CHECK(detectionCells(100, 100, 0, 19) == 0);
  // Noise holds corners everywhere: an empty image gets exactly one corner per such cell.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> grey(0, 255);
  // Plain variables, not a structured binding: CAPTURE's lambda cannot capture one before C++20's
  // rule reached every compiler (clang 16).
  for (const auto& size_case : {std::tuple{160, 120, 40, 19}, std::tuple{157, 113, 23, 7}, std::tuple{96, 64, 40, 19},
                                std::tuple{41, 39, 16, 2}}) {
    const int w = std::get<0>(size_case);
    const int h = std::get<1>(size_case);
    const int grid = std::get<2>(size_case);
    const int border = std::get<3>(size_case);
    CAPTURE(w);
    CAPTURE(grid);
    GrayImage image(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) image(x, y) = static_cast<std::uint8_t>(grey(rng));
    DetectorParams params;
    params.border_px = border;
    params.min_threshold = 0;  // down to threshold 0, so that every cell with room finds its corner
    GridDetector detector(w, h, grid);
    std::vector<Eigen::Vector2f> corners;
    corners.reserve(1000);
    CHECK(detector.detect(image.view(), {}, params, 1000, corners) == detectionCells(w, h, grid, border));
  }
}
