#pragma once
// JSON encoders for the messages of formats/foxglove/foxglove_schemas.h. Each writes one complete
// message into a caller-owned string, replacing its content; a string reserved once for the largest
// message (the *MaxBytes functions) is never reallocated, so encoding a frame allocates nothing.
// Numbers are written in their shortest round-trip form (the text reads back to the same double, as
// in our trajectory files); a non-finite number is written as null. Times are sensor time in
// nanoseconds, written as {"sec", "nsec"} (negative times as 0: the schemas allow none).

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "voca/geometry/se3.h"
#include "voca/motion/motion_field.h"

namespace voca::foxglove {

// Base64 (RFC 4648, with padding) of bytes, appended to out.
void appendBase64(std::span<const std::uint8_t> bytes, std::string& out);
constexpr std::size_t base64Size(std::size_t bytes) { return (bytes + 2) / 3 * 4; }

// foxglove.CompressedImage.
void writeCompressedImage(std::int64_t t_ns, std::string_view frame_id, std::string_view format,
                          std::span<const std::uint8_t> data, std::string& out);
std::size_t compressedImageMaxBytes(std::size_t data_bytes);

// foxglove.PoseInFrame: pose is T_frame_body.
void writePoseInFrame(std::int64_t t_ns, std::string_view frame_id, const SE3d& pose, std::string& out);

// foxglove.PosesInFrame, poses oldest first.
void writePosesInFrame(std::int64_t t_ns, std::string_view frame_id, std::span<const SE3d> poses, std::string& out);
std::size_t posesInFrameMaxBytes(std::size_t poses);

// foxglove.FrameTransform: the child frame's pose in the parent frame (T_parent_child).
void writeFrameTransform(std::int64_t t_ns, std::string_view parent_frame_id, std::string_view child_frame_id,
                         const SE3d& T_parent_child, std::string& out);

// foxglove.PointCloud of 3-D points (x, y, z as float32, 12 bytes a point) in frame_id.
void writePointCloud(std::int64_t t_ns, std::string_view frame_id, std::span<const Eigen::Vector3f> points,
                     std::string& out);
std::size_t pointCloudMaxBytes(std::size_t points);

// foxglove.ImageAnnotations with a motion field's past-reference vectors: for each block with a
// non-zero vector, a segment from where its content was in the previous frame (centre - vector) to
// its centre; green, or red for a vector flagged as an outlier. Zero vectors and future references
// are left out.
void writeMotionVectorAnnotations(std::int64_t t_ns, std::span<const MotionBlock> blocks, std::string& out);
std::size_t motionVectorAnnotationsMaxBytes(std::size_t blocks);

// voca.FrameStats.
struct FrameStats {
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  std::string_view state;  // "tracking", "reset" or "lost"
  bool keyframe = false;
  double decode_ms = 0.0, frontend_ms = 0.0, backend_ms = 0.0, end_to_end_ms = 0.0;
  int tracks_left = 0, tracks_right = 0;
  int landmarks = 0, keyframes = 0, inliers = 0;
  std::int64_t dropped = 0, damaged = 0, view_dropped = 0;
};
void writeFrameStats(const FrameStats& stats, std::string& out);

// Enough for any message of a fixed size (pose, transform, statistics).
inline constexpr std::size_t kSmallMessageMaxBytes = 1024;

}  // namespace voca::foxglove
