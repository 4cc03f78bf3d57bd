#include "voca/backend/stereo_residuals.h"

namespace voca::backend {

StereoResiduals::StereoResiduals(const StereoRig& rig, double obs_std_dev_px, double huber_px)
    : huber_px_(huber_px), inv_var_(1.0 / (obs_std_dev_px * obs_std_dev_px)) {
  for (int c = 0; c < 2; ++c) cameras_[static_cast<std::size_t>(c)] = rig.cameras[static_cast<std::size_t>(c)].camera;
  T_cam0_cam_[0] = SE3d();
  T_cam0_cam_[1] = rig.T_cam0_cam1();
}

}  // namespace voca::backend
