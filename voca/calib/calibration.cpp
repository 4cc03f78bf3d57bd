#include "voca/calib/calibration.h"

#include "voca/core/error.h"

namespace voca {

SE3d StereoRig::T_cam0_cam1() const {
  if (cameras.size() < 2) {
    throw InputError(source + ": a stereo rig needs two cameras, this calibration has " +
                     std::to_string(cameras.size()));
  }
  return cameras[0].T_body_cam.inverse() * cameras[1].T_body_cam;
}

}  // namespace voca
