#pragma once
// Helpers shared by the calibration readers (not part of the public interface).

#include <Eigen/Core>
#include <string>

#include "voca/geometry/se3.h"

namespace voca::calib_internal {

// Empty when m is a rigid transform to the precision calibration files are printed with
// (orthonormal rotation with determinant +1 and bottom row 0 0 0 1, within 1e-3), else what is wrong.
std::string rigidTransformProblem(const Eigen::Matrix4d& m);

// The rotation is re-orthonormalised, so a matrix printed with a few digits gives an exact rotation.
SE3d toSE3(const Eigen::Matrix4d& m);

// A rig needs at least cam0 and cam1.
constexpr int kMinCameras = 2;

// The largest image width or height a calibration may give (px): beyond any camera, and small enough
// that the pipeline's per-image buffers can be allocated (H.264's largest level codes 8192x4320).
constexpr int kMaxImageSide = 16384;

}  // namespace voca::calib_internal
