#include "voca/backend/stereo_residuals.h"

namespace voca::backend {

WindowPoses StereoResiduals::windowPoses(const Window& window) const {
  WindowPoses poses;
  for (int f = 0; f < kMaxWindowFrames; ++f) {
    FramePose& pose = poses[static_cast<std::size_t>(f)];
    pose.T_w_c0.set(window[f].T_w_c);
    for (std::size_t c = 0; c < 2; ++c) pose.R_cam_w[c].noalias() = cam0_cam_[c].R_inv * pose.T_w_c0.R_inv;
  }
  return poses;
}

StereoResiduals::StereoResiduals(const StereoRig& rig, double obs_std_dev_px, double huber_px)
    : huber_px_(huber_px), inv_var_(1.0 / (obs_std_dev_px * obs_std_dev_px)) {
  for (std::size_t c = 0; c < 2; ++c) {
    cameras_[c] = rig.cameras[c].camera;
    cameras_[c].setFastAngle(true);
  }
  T_cam0_cam_[0] = SE3d();
  T_cam0_cam_[1] = rig.T_cam0_cam1();
  for (std::size_t c = 0; c < 2; ++c) {
    cam0_cam_[c].set(T_cam0_cam_[c]);
    offset_cam_[c] = cam0_cam_[c].R_inv * cam0_cam_[c].t;
  }
}

}  // namespace voca::backend
