#include "voca/motion/motion_field.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace voca {

namespace {

int floorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Median of the first n values (reorders them).
float medianOf(float* values, std::size_t n) {
  const std::size_t mid = n / 2;
  std::nth_element(values, values + mid, values + n);
  const float upper = values[mid];
  if (n % 2 == 1) return upper;
  const float lower = *std::max_element(values, values + mid);
  return 0.5f * (lower + upper);
}

// The cells of a grid of kCell-pixel cells (cells_x by cells_y) whose centre lies in the rectangle
// [x, right) x [y, bottom): half-open ranges [cx0, cx1) x [cy0, cy1).
struct CellRange {
  int cx0, cx1, cy0, cy1;
};
template <int kCell>
CellRange cellsOf(int x, int y, int right, int bottom, int cells_x, int cells_y) {
  return {std::max(0, floorDiv(x - kCell / 2 + kCell - 1, kCell)),
          std::min(cells_x, floorDiv(right - 1 - kCell / 2, kCell) + 1),
          std::max(0, floorDiv(y - kCell / 2 + kCell - 1, kCell)),
          std::min(cells_y, floorDiv(bottom - 1 - kCell / 2, kCell) + 1)};
}

}  // namespace

const char* pictureTypeName(PictureType type) {
  switch (type) {
    case PictureType::kI:
      return "I";
    case PictureType::kP:
      return "P";
    case PictureType::kB:
      return "B";
    case PictureType::kUnknown:
      break;
  }
  return "?";
}

MotionField::MotionField(int max_width, int max_height) : max_width_(max_width), max_height_(max_height) {
  if (max_width < 0 || max_height < 0) throw std::invalid_argument("MotionField: negative capacity");
  const std::size_t cells_x = static_cast<std::size_t>((max_width + kCellPx - 1) / kCellPx);
  const std::size_t cells_y = static_cast<std::size_t>((max_height + kCellPx - 1) / kCellPx);
  const std::size_t cells = cells_x * cells_y;
  // At most one block per 4x4 cell and reference direction (the smallest codec partition).
  blocks_.reserve(2 * cells);
  grid_.assign(cells, kNoBlock);
  qp_grid_.assign(static_cast<std::size_t>((max_width + kQpCellPx - 1) / kQpCellPx) *
                      static_cast<std::size_t>((max_height + kQpCellPx - 1) / kQpCellPx),
                  kNoQp);
  scratch_x_.resize(2 * cells);
  scratch_y_.resize(2 * cells);
  visit_stamp_.assign(2 * cells, 0);
}

MotionField::MotionField(const MotionField& other) : MotionField(other.max_width_, other.max_height_) {
  copyFrom(other);
}

MotionField& MotionField::operator=(const MotionField& other) {
  if (this == &other) return *this;
  if (max_width_ != other.max_width_ || max_height_ != other.max_height_) {
    *this = MotionField(other.max_width_, other.max_height_);
  }
  copyFrom(other);
  return *this;
}

void MotionField::reset(int width, int height, PictureType type) {
  if (width < 0 || height < 0 || width > max_width_ || height > max_height_) {
    throw std::length_error("MotionField: frame larger than the capacity set at construction");
  }
  width_ = width;
  height_ = height;
  grid_stride_ = static_cast<std::size_t>((width + kCellPx - 1) / kCellPx);
  qp_stride_ = static_cast<std::size_t>((width + kQpCellPx - 1) / kQpCellPx);
  type_ = type;
  blocks_.clear();
  has_qp_ = false;  // the QP grid is cleared by the frame's first setQp(), so frames without QP pay nothing
  const std::size_t cells = grid_stride_ * static_cast<std::size_t>((height + kCellPx - 1) / kCellPx);
  std::fill_n(grid_.begin(), static_cast<std::ptrdiff_t>(cells), kNoBlock);
}

bool MotionField::addBlock(int x, int y, int w, int h, float dx, float dy, RefDirection ref) {
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + w, width_), y1 = std::min(y + h, height_);
  if (x1 <= x0 || y1 <= y0 || blocks_.size() == blocks_.capacity()) return false;
  MotionBlock block;
  block.x = static_cast<std::int16_t>(x0);
  block.y = static_cast<std::int16_t>(y0);
  block.w = static_cast<std::int16_t>(x1 - x0);
  block.h = static_cast<std::int16_t>(y1 - y0);
  block.dx = dx;
  block.dy = dy;
  block.ref = ref;
  blocks_.push_back(block);
  return true;
}

void MotionField::finalize() {
  const int cells_x = static_cast<int>(grid_stride_);
  const int cells_y = (height_ + kCellPx - 1) / kCellPx;
  // Future-reference blocks first so that past-reference ones (the forward flow the tracker wants)
  // win where both exist.
  for (const RefDirection pass : {RefDirection::kFuture, RefDirection::kPast}) {
    for (std::size_t i = 0; i < blocks_.size(); ++i) {
      const MotionBlock& b = blocks_[i];
      if (b.ref != pass) continue;
      // A cell belongs to the block containing its centre. Blocks touching the right/bottom image
      // edge are extended to the grid edge so cells straddling a border that is not a multiple of
      // kCellPx are still covered.
      int right = b.x + b.w, bottom = b.y + b.h;
      if (right >= width_) right = cells_x * kCellPx;
      if (bottom >= height_) bottom = cells_y * kCellPx;
      const CellRange r = cellsOf<kCellPx>(b.x, b.y, right, bottom, cells_x, cells_y);
      for (int cy = r.cy0; cy < r.cy1; ++cy) {
        std::int32_t* row = grid_.data() + static_cast<std::size_t>(cy) * grid_stride_;
        for (int cx = r.cx0; cx < r.cx1; ++cx) row[cx] = static_cast<std::int32_t>(i);
      }
    }
  }
  // A codec partition never straddles macroblocks, so any pixel of the block gives its quantiser.
  for (MotionBlock& b : blocks_) b.qp = qpAt(b.x + b.w / 2, b.y + b.h / 2);
}

bool MotionField::setQp(int x, int y, int w, int h, int qp) {
  if (qp < 0 || qp > 32767) return false;
  const int cells_x = static_cast<int>(qp_stride_);
  const int cells_y = (height_ + kQpCellPx - 1) / kQpCellPx;
  if (!has_qp_) {
    std::fill_n(qp_grid_.begin(), static_cast<std::ptrdiff_t>(qp_stride_ * static_cast<std::size_t>(cells_y)), kNoQp);
    has_qp_ = true;
  }
  // Clipped like addBlock(), and extended to the grid edge at the right/bottom image border as in finalize().
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  int right = std::min(x + w, width_), bottom = std::min(y + h, height_);
  if (right <= x0 || bottom <= y0) return true;
  if (right >= width_) right = cells_x * kQpCellPx;
  if (bottom >= height_) bottom = cells_y * kQpCellPx;
  const CellRange r = cellsOf<kQpCellPx>(x0, y0, right, bottom, cells_x, cells_y);
  for (int cy = r.cy0; cy < r.cy1; ++cy) {
    std::int16_t* row = qp_grid_.data() + static_cast<std::size_t>(cy) * qp_stride_;
    std::fill(row + r.cx0, row + std::max(r.cx0, r.cx1), static_cast<std::int16_t>(qp));
  }
  return true;
}

std::optional<Eigen::Vector2f> MotionField::forwardFlowAt(float x, float y) const {
  // The pixel containing (x, y) is floor(x + 0.5); checking the range first keeps the conversion to
  // int defined for any float (and rejects NaN).
  const float px = std::floor(x + 0.5f), py = std::floor(y + 0.5f);
  if (!(px >= 0.f && py >= 0.f && px < static_cast<float>(width_) && py < static_cast<float>(height_))) {
    return std::nullopt;
  }
  const MotionBlock* block = blockAt(static_cast<int>(px), static_cast<int>(py));
  if (block == nullptr) return std::nullopt;
  return Eigen::Vector2f(block->dx, block->dy);
}

void MotionField::copyFrom(const MotionField& other) {
  if (this == &other) return;
  if (other.blocks_.size() > blocks_.capacity() || other.width_ > max_width_ || other.height_ > max_height_) {
    throw std::length_error("MotionField::copyFrom: source larger than this field's capacity");
  }
  width_ = other.width_;
  height_ = other.height_;
  grid_stride_ = other.grid_stride_;
  type_ = other.type_;
  blocks_.assign(other.blocks_.begin(), other.blocks_.end());
  const std::size_t cells = grid_stride_ * static_cast<std::size_t>((height_ + kCellPx - 1) / kCellPx);
  std::copy_n(other.grid_.begin(), static_cast<std::ptrdiff_t>(cells), grid_.begin());
  qp_stride_ = other.qp_stride_;
  has_qp_ = other.has_qp_;
  if (has_qp_) {
    const std::size_t qp_cells = qp_stride_ * static_cast<std::size_t>((height_ + kQpCellPx - 1) / kQpCellPx);
    std::copy_n(other.qp_grid_.begin(), static_cast<std::ptrdiff_t>(qp_cells), qp_grid_.begin());
  }
}

int MotionField::flagOutliers(const OutlierParams& params) {
  const int cells_x = static_cast<int>(grid_stride_);
  const int cells_y = (height_ + kCellPx - 1) / kCellPx;
  const int radius_cells = std::max(0, params.radius_px) / kCellPx;
  int flagged = 0;

  for (const RefDirection dir : {RefDirection::kPast, RefDirection::kFuture}) {
    // Global median of this direction, the fallback reference for sparse neighbourhoods.
    std::size_t n = 0;
    for (const MotionBlock& b : blocks_) {
      if (b.ref != dir) continue;
      scratch_x_[n] = b.dx;
      scratch_y_[n] = b.dy;
      ++n;
    }
    if (n == 0) continue;
    const float global_x = medianOf(scratch_x_.data(), n);
    const float global_y = medianOf(scratch_y_.data(), n);

    for (std::size_t i = 0; i < blocks_.size(); ++i) {
      MotionBlock& block = blocks_[i];
      if (block.ref != dir) continue;
      // Fresh stamp per block so each neighbour is counted once although it covers several cells.
      if (++stamp_ == 0) {
        std::fill(visit_stamp_.begin(), visit_stamp_.end(), 0u);
        stamp_ = 1;
      }
      visit_stamp_[i] = stamp_;
      // The pixel nearest the centre (the centre of an even-sized block lies between two pixels).
      const int ccx = static_cast<int>(std::lround(block.centreX())) / kCellPx;
      const int ccy = static_cast<int>(std::lround(block.centreY())) / kCellPx;
      std::size_t count = 0;
      for (int cy = std::max(0, ccy - radius_cells); cy <= std::min(cells_y - 1, ccy + radius_cells); ++cy) {
        for (int cx = std::max(0, ccx - radius_cells); cx <= std::min(cells_x - 1, ccx + radius_cells); ++cx) {
          const std::int32_t j = grid_[static_cast<std::size_t>(cy) * grid_stride_ + static_cast<std::size_t>(cx)];
          if (j == kNoBlock || visit_stamp_[static_cast<std::size_t>(j)] == stamp_) continue;
          visit_stamp_[static_cast<std::size_t>(j)] = stamp_;
          const MotionBlock& other = blocks_[static_cast<std::size_t>(j)];
          if (other.ref != dir) continue;
          scratch_x_[count] = other.dx;
          scratch_y_[count] = other.dy;
          ++count;
        }
      }
      float ref_x = global_x, ref_y = global_y;
      if (count >= static_cast<std::size_t>(std::max(1, params.min_neighbours))) {
        ref_x = medianOf(scratch_x_.data(), count);
        ref_y = medianOf(scratch_y_.data(), count);
      }
      const float deviation = std::hypot(block.dx - ref_x, block.dy - ref_y);
      const float threshold = std::max(params.abs_threshold_px, params.rel_threshold * std::hypot(ref_x, ref_y));
      block.outlier = deviation > threshold;
      flagged += block.outlier ? 1 : 0;
    }
  }
  return flagged;
}

const MotionField* MotionPriorBridge::prior(const MotionField& field, int frames_missing_before, bool& bridged) {
  if (field.hasVectors()) {
    if (enabled_ || flag_outliers_) {
      last_.copyFrom(field);
      have_last_ = enabled_;
    }
    if (frames_missing_before > 0) return nullptr;
    if (!flag_outliers_) return &field;
    last_.flagOutliers();
    return &last_;
  }
  if (frames_missing_before > 0) return nullptr;
  if (enabled_ && have_last_ && field.pictureType() == PictureType::kI) {
    bridged = true;
    return &last_;
  }
  return nullptr;
}

}  // namespace voca
