#include "voca/backend/stereo_residuals.h"

namespace voca::backend {

WindowPoses windowPoses(const Window& window) {
  WindowPoses poses;
  for (int f = 0; f < kMaxWindowFrames; ++f) poses[static_cast<std::size_t>(f)].set(window[f].T_w_c);
  return poses;
}

StereoResiduals::StereoResiduals(const StereoRig& rig, double obs_std_dev_px, double huber_px)
    : huber_px_(huber_px), inv_var_(1.0 / (obs_std_dev_px * obs_std_dev_px)) {
  for (int c = 0; c < 2; ++c) cameras_[static_cast<std::size_t>(c)] = rig.cameras[static_cast<std::size_t>(c)].camera;
  T_cam0_cam_[0] = SE3d();
  T_cam0_cam_[1] = rig.T_cam0_cam1();
  for (std::size_t c = 0; c < 2; ++c) cam0_cam_[c].set(T_cam0_cam_[c]);
}

}  // namespace voca::backend
