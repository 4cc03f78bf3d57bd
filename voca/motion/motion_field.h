#pragma once
// Codec-agnostic per-block motion of one decoded frame, with O(1) lookup of the block covering a pixel.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace voca {

// Frame-level coding type as the decoder reported it.
enum class PictureType : std::uint8_t { kUnknown, kI, kP, kB };

// Which reference a block's vector points into.
enum class RefDirection : std::uint8_t { kPast, kFuture };

const char* pictureTypeName(PictureType type);

// One inter-predicted block. (x, y, w, h) is its rectangle in the current frame: the pixels x..x+w-1
// and y..y+h-1, clipped to the image; (dx, dy) is the forward displacement in pixels: a point of the reference frame at
// p is at p + (dx, dy) in this frame when ref is kPast (the codec vector negated, DESIGN.md section 4). For kFuture the
// vector is stored the same way relative to the future reference: the point of the future reference at p is at p + (dx,
// dy) here.
struct MotionBlock {
  std::int16_t x = 0, y = 0, w = 0, h = 0;
  float dx = 0.f, dy = 0.f;
  RefDirection ref = RefDirection::kPast;
  bool outlier = false;  // set by MotionField::flagOutliers()
  // The quantiser of the macroblock holding the block's centre (codec units: H.264 QP 0..51, MPEG-2/4
  // quantiser scale), or kNoQp when the decoder did not export it. Set by MotionField::finalize().
  std::int16_t qp = -1;

  // Centre in pixel-centre coordinates ((0, 0) is the centre of the top-left pixel): a 16-pixel
  // block at x = 0 has its centre at 7.5.
  float centreX() const { return static_cast<float>(x) + 0.5f * static_cast<float>(w - 1); }
  float centreY() const { return static_cast<float>(y) + 0.5f * static_cast<float>(h - 1); }
};

// Median thresholding of vectors (the paper's Fig. 3): a block is flagged when its displacement
// differs from the component-wise median of the blocks around it by more than
// max(abs_threshold_px, rel_threshold * |median|). Too few neighbours -> the global median is used.
struct OutlierParams {
  int radius_px = 24;      // neighbourhood: blocks whose centre lies within this box radius
  int min_neighbours = 4;  // below this the global median of the frame is the reference
  float abs_threshold_px = 2.f;
  float rel_threshold = 0.5f;
};

// The motion field of one frame. Capacity (max image size) is fixed at construction; reset(),
// addBlock(), setQp(), finalize(), copyFrom() and flagOutliers() never allocate afterwards. Lookups go
// through a grid of kCellPx x kCellPx cells holding the index of the block covering each cell
// (past references win over future ones), so blockAt() is O(1); a second grid, one cell per 16x16
// macroblock, holds the quantiser (qpAt()), which codecs set per macroblock.
class MotionField {
 public:
  static constexpr int kCellPx = 4;
  static constexpr std::int32_t kNoBlock = -1;
  static constexpr std::int16_t kNoQp = -1;
  static constexpr int kQpCellPx = 16;

  MotionField() = default;
  MotionField(int max_width, int max_height);
  // Copies keep the capacity of the source: a plain vector copy would shrink the block storage to
  // the source's block count, and the copy would then silently refuse blocks of a later frame.
  MotionField(const MotionField& other);
  MotionField& operator=(const MotionField& other);
  MotionField(MotionField&&) noexcept = default;
  MotionField& operator=(MotionField&&) noexcept = default;

  int maxWidth() const { return max_width_; }
  int maxHeight() const { return max_height_; }
  std::size_t blockCapacity() const { return blocks_.capacity(); }

  // Start a new frame: no blocks, every pixel "no vector". Throws std::length_error when the size
  // exceeds the capacity.
  void reset(int width, int height, PictureType type);

  // Add a block given as a rectangle in the current frame (may reach outside the image: it is clipped)
  // and its forward displacement. Returns false (and ignores the block) when it lies entirely
  // outside the image or the block capacity is used up.
  bool addBlock(int x, int y, int w, int h, float dx, float dy, RefDirection ref = RefDirection::kPast);

  // Record the quantiser of a coding block (a macroblock: the rectangle may reach outside the image
  // and is clipped; the kQpCellPx cells whose centre it contains take qp). Values outside [0, 32767] are refused
  // (returns false). Call between reset() and finalize(); cells never set stay kNoQp.
  bool setQp(int x, int y, int w, int h, int qp);

  // Rasterise the blocks into the lookup grid and give each block the quantiser at its centre. Call
  // once after the last addBlock() and setQp() of a frame.
  void finalize();

  // The block covering pixel (x, y), or nullptr for "no vector" (intra block, I-frame, uncovered
  // or outside the image). O(1).
  const MotionBlock* blockAt(int x, int y) const {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return nullptr;
    const std::int32_t index = grid_[static_cast<std::size_t>(y / kCellPx) * grid_stride_ + x / kCellPx];
    return index == kNoBlock ? nullptr : &blocks_[static_cast<std::size_t>(index)];
  }
  // The quantiser of the coding block covering pixel (x, y), or kNoQp (not exported, outside). O(1).
  std::int16_t qpAt(int x, int y) const {
    if (!has_qp_ || x < 0 || y < 0 || x >= width_ || y >= height_) return kNoQp;
    return qp_grid_[static_cast<std::size_t>(y / kQpCellPx) * qp_stride_ + x / kQpCellPx];
  }
  bool hasQp() const { return has_qp_; }
  // Forward flow at a sub-pixel position in pixel-centre coordinates ((0, 0) is the centre of the
  // top-left pixel, so pixel (i, j) spans [i - 0.5, i + 0.5) x [j - 0.5, j + 0.5)): the block of the
  // pixel containing it, or nullopt for "no vector".
  std::optional<Eigen::Vector2f> forwardFlowAt(float x, float y) const;

  std::span<const MotionBlock> blocks() const { return blocks_; }
  std::span<MotionBlock> blocks() { return blocks_; }
  bool hasVectors() const { return !blocks_.empty(); }
  int width() const { return width_; }
  int height() const { return height_; }
  PictureType pictureType() const { return type_; }

  // Copy another field's blocks, grid, size and flags into this one without allocating (capacity
  // must suffice: throws std::length_error otherwise).
  void copyFrom(const MotionField& other);

  // Set MotionBlock::outlier by median thresholding; returns the number of flagged blocks.
  int flagOutliers(const OutlierParams& params = {});

 private:
  int max_width_ = 0, max_height_ = 0;
  int width_ = 0, height_ = 0;
  std::size_t grid_stride_ = 0;
  PictureType type_ = PictureType::kUnknown;
  std::vector<MotionBlock> blocks_;
  std::vector<std::int32_t> grid_;
  std::size_t qp_stride_ = 0;
  std::vector<std::int16_t> qp_grid_;  // valid when has_qp_ (set by the first setQp() of the frame)
  bool has_qp_ = false;
  // Scratch for flagOutliers(), sized at construction.
  std::vector<float> scratch_x_, scratch_y_;
  std::vector<std::uint32_t> visit_stamp_;
  std::uint32_t stamp_ = 0;
};

// The motion prior of each frame of one camera's stream, carried over I-frames (the paper's
// "Bridging I-frames"); the one place that decides which vectors predict a frame's motion. Feed
// every frame's field in stream order. No allocation after construction.
class MotionPriorBridge {
 public:
  MotionPriorBridge() = default;
  // enabled = false: a frame's own vectors or none, nothing is carried over. flag_outliers: every
  // field handed out has its blocks flagged by MotionField::flagOutliers (on a copy; the input stays
  // untouched), so a consumer can distrust vectors that disagree with their neighbourhood.
  MotionPriorBridge(int max_width, int max_height, bool enabled = true, bool flag_outliers = false)
      : last_(max_width, max_height), enabled_(enabled), flag_outliers_(flag_outliers) {}

  // The field whose vectors give this frame's motion from the previous frame the tracker saw:
  //  - the frame's own field when it has vectors (and, when enabled, remembered for later I-frames,
  //    whatever the picture type);
  //  - for an I-frame without vectors, the last remembered field; `bridged` is set to true;
  //  - nullptr otherwise, and always after a gap (frames_missing_before > 0): the vectors then
  //    describe the motion from a picture the tracker never saw.
  // The result stays valid until the next call.
  const MotionField* prior(const MotionField& field, int frames_missing_before, bool& bridged);
  // Forgets the remembered field.
  void clear() { have_last_ = false; }

 private:
  MotionField last_;
  bool have_last_ = false;
  bool enabled_ = true;
  bool flag_outliers_ = false;
};

}  // namespace voca
