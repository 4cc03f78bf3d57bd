#include "voca/calib/calibration.h"

#include "voca/core/error.h"

namespace voca {

void StereoRig::requireStereo() const {
  if (cameras.size() < 2) {
    throw InputError(source + ": need a stereo calibration (two cameras), this one has " +
                     std::to_string(cameras.size()));
  }
}

SE3d StereoRig::T_cam0_cam1() const {
  requireStereo();
  return cameras[0].T_body_cam.inverse() * cameras[1].T_body_cam;
}

}  // namespace voca
