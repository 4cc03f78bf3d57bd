#include "voca/synth/motion.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "voca/core/quantile.h"

namespace voca::synth {

namespace {

struct Wave {
  double amplitude;
  double period_s;
  double phase;
};

// One scalar motion channel: a linear drift (rad/s for a turning camera) plus sinusoids.
struct Channel {
  double rate = 0.0;
  std::vector<Wave> waves;

  double value(double t) const {
    double sum = rate * t;
    for (const Wave& w : waves) sum += w.amplitude * std::sin(2.0 * std::numbers::pi * t / w.period_s + w.phase);
    return sum;
  }
  double maxExcursion() const {
    double sum = 0.0;
    for (const Wave& w : waves) sum += std::abs(w.amplitude);
    return sum;
  }
};

struct PresetSpec {
  Channel position[3];  // x, y, z about the room centre, metres
  Channel yaw, pitch, roll;
};

// The presets. Periods are incommensurate so the motion never visibly repeats within a sequence;
// small fast terms in `gentle` are hand tremor.
PresetSpec presetSpec(MotionPreset preset) {
  PresetSpec s;
  switch (preset) {
    case MotionPreset::kGentle:
      // About 0.3-0.5 m/s and 0.1-0.3 rad/s: a few px/frame at 20 Hz.
      s.position[0].waves = {{0.8, 11.0, 0.0}, {0.2, 4.3, 1.0}, {0.003, 0.45, 0.3}};
      s.position[1].waves = {{0.6, 9.0, 0.5}, {0.15, 3.7, 2.0}, {0.003, 0.55, 1.1}};
      s.position[2].waves = {{0.2, 7.0, 2.0}, {0.05, 2.9, 0.0}, {0.002, 0.6, 2.2}};
      s.yaw.waves = {{0.5, 13.0, 0.0}, {0.1, 5.1, 0.7}, {0.004, 0.5, 0.0}};
      s.pitch.waves = {{0.1, 7.3, 0.4}, {0.03, 2.3, 1.5}, {0.003, 0.42, 0.9}};
      s.roll.waves = {{0.05, 6.1, 1.2}, {0.02, 1.9, 0.2}};
      break;
    case MotionPreset::kFastRotation:
      // Turning on the spot at 0.9 rad/s +- 0.95 rad/s and nodding: 0-45 px/frame at 20 Hz.
      s.position[0].waves = {{0.25, 6.0, 0.0}, {0.05, 2.1, 0.5}};
      s.position[1].waves = {{0.2, 7.7, 1.0}, {0.05, 2.6, 0.0}};
      s.position[2].waves = {{0.1, 5.3, 0.3}};
      s.yaw.rate = 0.9;
      s.yaw.waves = {{0.5, 3.3, 0.0}};
      s.pitch.waves = {{0.25, 2.7, 0.5}, {0.05, 1.1, 0.0}};
      s.roll.waves = {{0.12, 2.3, 0.0}};
      break;
    case MotionPreset::kAggressive:
      // Drone-like: up to about 3 m/s, fast yaw and banking.
      s.position[0].waves = {{1.8, 5.0, 0.0}, {0.3, 1.9, 0.7}};
      s.position[1].waves = {{1.3, 6.5, 1.0}, {0.25, 2.3, 0.0}};
      s.position[2].waves = {{0.4, 3.3, 0.0}, {0.1, 1.3, 1.4}};
      s.yaw.waves = {{0.6, 7.0, 0.0}, {0.35, 2.5, 0.5}};
      s.pitch.waves = {{0.2, 3.1, 0.8}, {0.05, 1.2, 0.0}};
      s.roll.waves = {{0.35, 2.7, 1.0}};
      break;
  }
  return s;
}

Eigen::Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
Eigen::Matrix3d rotX(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

}  // namespace

std::optional<MotionPreset> parseMotionPreset(std::string_view name) {
  if (name == "gentle") return MotionPreset::kGentle;
  if (name == "fast-rotation") return MotionPreset::kFastRotation;
  if (name == "aggressive") return MotionPreset::kAggressive;
  return std::nullopt;
}

std::string_view motionPresetName(MotionPreset preset) {
  switch (preset) {
    case MotionPreset::kGentle:
      return "gentle";
    case MotionPreset::kFastRotation:
      return "fast-rotation";
    case MotionPreset::kAggressive:
      return "aggressive";
  }
  return "unknown";
}

SE3d presetCameraPose(MotionPreset preset, double t_s, const RoomBox& room, double clearance_m) {
  const PresetSpec spec = presetSpec(preset);
  const Eigen::Vector3d center = room.center();
  const Eigen::Vector3d half = room.halfExtent();
  Eigen::Vector3d p;
  for (int a = 0; a < 3; ++a) {
    const double excursion = spec.position[a].maxExcursion();
    const double allowed = std::max(half[a] - clearance_m, 0.0);
    const double scale = excursion > allowed ? allowed / excursion : 1.0;
    p[a] = center[a] + scale * spec.position[a].value(t_s);
  }
  // Level camera looking along world +x: camera x = world -y, y = world -z, z = world +x.
  Eigen::Matrix3d level;
  level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  // Yaw about the world vertical, then pitch (about the camera x axis) and roll (about its optical axis).
  const Eigen::Matrix3d R = rotZ(spec.yaw.value(t_s)) * level * rotX(spec.pitch.value(t_s)) *
                            Eigen::AngleAxisd(spec.roll.value(t_s), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return SE3d(SO3d(R), p);
}

RoomPlacement placeInRoom(std::span<const Eigen::Vector3d> positions, const RoomBox& default_room, double clearance_m) {
  RoomPlacement placement;
  placement.room = default_room;
  if (positions.empty()) return placement;
  Eigen::Vector3d lo = positions.front();
  Eigen::Vector3d hi = positions.front();
  for (const Eigen::Vector3d& p : positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d needed_half = 0.5 * (hi - lo) + Eigen::Vector3d::Constant(clearance_m);
  const Eigen::Vector3d half = default_room.halfExtent().cwiseMax(needed_half);
  const Eigen::Vector3d center = default_room.center();
  // Keep the floor where it was when the room grows upwards, so heights stay plausible.
  Eigen::Vector3d new_center = center;
  new_center.z() = default_room.min.z() + half.z();
  placement.room.min = new_center - half;
  placement.room.max = new_center + half;
  placement.offset = new_center - 0.5 * (lo + hi);
  return placement;
}

ImageMotionStats measureImageMotion(const Scene& scene, const RayTable& rays, const Project& project,
                                    std::span<const SE3d> T_world_cam, int grid_step_px) {
  std::vector<double> flow;
  for (std::size_t i = 0; i + 1 < T_world_cam.size(); ++i) {
    const SE3d T_next_cam_world = T_world_cam[i + 1].inverse();
    for (int y = grid_step_px / 2; y < rays.height(); y += grid_step_px) {
      for (int x = grid_step_px / 2; x < rays.width(); x += grid_step_px) {
        const float depth = rayDepth(scene, rays, T_world_cam[i], x, y);
        if (depth <= 0.0f) continue;
        const Eigen::Vector3d p_world = T_world_cam[i] * (rays.bearing(x, y).cast<double>() * depth);
        Eigen::Vector2d uv;
        if (!project(T_next_cam_world * p_world, uv)) continue;
        flow.push_back((uv - Eigen::Vector2d(x, y)).norm());
      }
    }
  }
  ImageMotionStats stats;
  stats.samples = flow.size();
  if (flow.empty()) return stats;
  stats.median_px = quantileInPlace(flow, 0.5);
  stats.p90_px = quantileInPlace(flow, 0.9);
  stats.max_px = quantileInPlace(flow, 1.0);
  return stats;
}

}  // namespace voca::synth
