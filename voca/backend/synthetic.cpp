#include "voca/backend/synthetic.h"

#include <cmath>
#include <random>

namespace voca {

SE3d syntheticCameraPose(double t_s, double motion_scale) {
  const double s = motion_scale;
  const double t = t_s;
  const Eigen::Vector3d position(1.2 * std::sin(0.21 * s * t) + 0.2 * std::sin(0.9 * s * t),
                                 0.9 * std::sin(0.17 * s * t + 0.5) + 0.15 * std::cos(1.1 * s * t),
                                 0.8 + 0.25 * std::sin(0.33 * s * t));
  const double yaw = 2.0 * M_PI * t / 30.0 * s + 0.25 * std::sin(0.5 * s * t);
  const double pitch = 0.12 * std::sin(0.7 * s * t);
  const double roll = 0.08 * std::sin(0.45 * s * t + 1.0);
  // Camera axes (x right, y down, z forward) for yaw = 0: forward along world x, z up.
  Eigen::Matrix3d base;
  base.col(0) = Eigen::Vector3d(0, -1, 0);
  base.col(1) = Eigen::Vector3d(0, 0, -1);
  base.col(2) = Eigen::Vector3d(1, 0, 0);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix() * base;
  return SE3d(R, position);
}

SyntheticObservations makeSyntheticObservations(const StereoRig& rig, const SyntheticObservationsConfig& config) {
  std::mt19937 rng(config.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Points on the walls, floor and ceiling of the room and a few pillars' worth of clutter.
  const Eigen::Vector3d lo(-5.0, -4.0, -1.0), hi(5.0, 4.0, 3.0);
  std::vector<Eigen::Vector3d> points;
  points.reserve(static_cast<std::size_t>(config.num_points));
  for (int i = 0; i < config.num_points; ++i) {
    Eigen::Vector3d p(lo.x() + uniform(rng) * (hi.x() - lo.x()), lo.y() + uniform(rng) * (hi.y() - lo.y()),
                      lo.z() + uniform(rng) * (hi.z() - lo.z()));
    const int face = static_cast<int>(uniform(rng) * 7.0);
    if (face < 6) {
      const int axis = face / 2;
      p(axis) = face % 2 == 0 ? lo(axis) : hi(axis);
    } else if (std::hypot(p.x(), p.y()) < 2.5) {
      p.head<2>() *= 2.5 / std::max(std::hypot(p.x(), p.y()), 1e-3);  // clutter away from the path
    }
    points.push_back(p);
  }

  const SE3d T_body_cam0 = rig.cameras[0].T_body_cam;
  const std::array<SE3d, 2> T_cam0_cam{SE3d(), rig.T_cam0_cam1()};
  const int num_frames = static_cast<int>(config.duration_s * config.fps);
  SyntheticObservations out;
  out.t_ns.reserve(static_cast<std::size_t>(num_frames));
  out.T_world_body.reserve(static_cast<std::size_t>(num_frames));
  out.frames.resize(static_cast<std::size_t>(num_frames));

  std::vector<std::uint64_t> track_of(points.size(), 0);  // 0 = not tracked
  std::uint64_t next_id = 1;
  const int width = rig.cameras[0].width, height = rig.cameras[0].height;
  const int cells_x = (width + config.grid_px - 1) / config.grid_px;
  const int cells_y = (height + config.grid_px - 1) / config.grid_px;
  std::vector<char> occupied;
  const double margin = 10.0;
  const auto visible = [&](int cam, const SE3d& T_w_c0, const Eigen::Vector3d& p_w, Eigen::Vector2d& uv) {
    const SE3d T_c_w = (T_w_c0 * T_cam0_cam[static_cast<std::size_t>(cam)]).inverse();
    const Eigen::Vector3d p_c = T_c_w * p_w;
    if (p_c.z() < 0.3) return false;
    const CameraCalibration& calib = rig.cameras[static_cast<std::size_t>(cam)];
    if (!calib.camera.project(p_c, uv)) return false;
    return uv.x() >= margin && uv.y() >= margin && uv.x() < calib.width - margin && uv.y() < calib.height - margin;
  };

  for (int k = 0; k < num_frames; ++k) {
    const double t = k / config.fps;
    const SE3d T_w_c0 = syntheticCameraPose(t, config.motion_scale);
    out.t_ns.push_back(static_cast<std::int64_t>(std::llround(t * 1e9)));
    out.T_world_body.push_back(T_w_c0 * T_body_cam0.inverse());
    TrackedStereoFrame& frame = out.frames[static_cast<std::size_t>(k)];
    frame.t_ns = out.t_ns.back();
    frame.frame_index = k;
    frame.reserve(static_cast<std::size_t>(config.max_points_per_frame));
    occupied.assign(static_cast<std::size_t>(cells_x * cells_y), 0);
    int count = 0;
    const auto emit = [&](std::size_t i, const Eigen::Vector2d& uv0) {
      const Eigen::Vector2d n0(gauss(rng), gauss(rng));
      frame.observations[0].push_back({track_of[i], (uv0 + config.noise_px * n0).cast<float>()});
      Eigen::Vector2d uv1;
      if (visible(1, T_w_c0, points[i], uv1)) {
        const Eigen::Vector2d n1(gauss(rng), gauss(rng));
        frame.observations[1].push_back({track_of[i], (uv1 + config.noise_px * n1).cast<float>()});
      }
      const int cx = static_cast<int>(uv0.x()) / config.grid_px, cy = static_cast<int>(uv0.y()) / config.grid_px;
      occupied[static_cast<std::size_t>(cy * cells_x + cx)] = 1;
      ++count;
    };
    // Continuing tracks first, then new ones in empty cells.
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (track_of[i] == 0) continue;
      Eigen::Vector2d uv0;
      if (!visible(0, T_w_c0, points[i], uv0) || count >= config.max_points_per_frame) {
        track_of[i] = 0;
        continue;
      }
      emit(i, uv0);
    }
    for (std::size_t i = 0; i < points.size() && count < config.max_points_per_frame; ++i) {
      if (track_of[i] != 0) continue;
      Eigen::Vector2d uv0;
      if (!visible(0, T_w_c0, points[i], uv0)) continue;
      const int cx = static_cast<int>(uv0.x()) / config.grid_px, cy = static_cast<int>(uv0.y()) / config.grid_px;
      if (occupied[static_cast<std::size_t>(cy * cells_x + cx)]) continue;
      track_of[i] = next_id++;
      emit(i, uv0);
    }
  }
  return out;
}

}  // namespace voca
