#pragma once
// Camera motion for synthetic sequences: smooth presets (handheld, fast rotation, drone-like),
// fitting a recorded trajectory into the room, and measuring the resulting image motion.

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "voca/geometry/se3.h"
#include "voca/synth/renderer.h"
#include "voca/synth/scene.h"

namespace voca::synth {

enum class MotionPreset { kGentle, kFastRotation, kAggressive };

std::optional<MotionPreset> parseMotionPreset(std::string_view name);  // "gentle", "fast-rotation", "aggressive"
std::string_view motionPresetName(MotionPreset preset);

// Pose T_world_cam at time t_s of a camera looking forward (x right, y down, z forward) for a
// preset: sums of sinusoids, so position and orientation are smooth (C-infinity) with realistic
// velocities. The path is centred in the room and scaled down where needed so that the camera
// stays at least clearance_m from every wall, the floor and the ceiling.
SE3d presetCameraPose(MotionPreset preset, double t_s, const RoomBox& room, double clearance_m);

// Where a recorded trajectory goes in the room: the room grows (never shrinks) so that every
// position, shifted by `offset`, is at least clearance_m inside; the trajectory's bounding box is
// centred in the room. The file's z axis is taken as up (EuRoC, TUM-VI ground truth).
struct RoomPlacement {
  RoomBox room;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // add to every position
};
RoomPlacement placeInRoom(std::span<const Eigen::Vector3d> positions, const RoomBox& default_room, double clearance_m);

// Image motion between consecutive frames: a grid of pixels is ray-cast into the scene at pose i
// and the hit points projected at pose i + 1 (static scene, so this is the true optical flow).
struct ImageMotionStats {
  double median_px = 0.0;
  double p90_px = 0.0;
  double max_px = 0.0;
  // Pixels measured over all pose pairs. 0 when no sampled scene point stayed in view from one pose
  // to the next (motion too fast to measure); the figures above are then 0 too, and meaningless.
  std::size_t samples = 0;
};
using Project = std::function<bool(const Eigen::Vector3d& p_cam, Eigen::Vector2d& uv)>;
ImageMotionStats measureImageMotion(const Scene& scene, const RayTable& rays, const Project& project,
                                    std::span<const SE3d> T_world_cam, int grid_step_px = 16);

}  // namespace voca::synth
