#pragma once
// The sliding window's frames: fixed slots (a slot index is the frame's block in every window-sized
// matrix and its bits in a landmark's observation mask), each with its pose, the first-estimate
// linearisation point of the marginalisation prior and its observations sorted by track id.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "voca/backend/backend_config.h"
#include "voca/core/tracked_frame.h"
#include "voca/geometry/se3.h"

namespace voca::backend {

// Bit of a landmark's observation mask for one camera of one window slot.
inline int maskBit(int frame, int cam) { return 2 * frame + cam; }
// Both cameras' bits of one window slot.
inline std::uint32_t frameBits(int frame) { return 3u << maskBit(frame, 0); }

struct Observation {
  std::uint64_t id = 0;
  Eigen::Vector2d px = Eigen::Vector2d::Zero();
};

struct WindowFrame {
  bool active = false;
  bool keyframe = false;
  bool in_prior = false;  // the prior's linearisation point T_lin is fixed (first estimate)
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  std::int64_t sequence = 0;  // order of creation
  SE3d T_w_c;
  SE3d T_w_c_lin;
  SE3d T_w_c_backup;
  std::array<std::vector<Observation>, 2> obs;  // sorted by id, capacity fixed

  // This frame's observation of a track in camera `cam`, or nullptr.
  const Observation* find(int cam, std::uint64_t id) const;
};

class Window {
 public:
  // Reserves every frame's observation lists (max_observations per camera), so nothing allocates later.
  explicit Window(int max_observations = 0);

  // Every slot inactive.
  void clear();
  // Takes a free slot for the frame (its finite observations, at most the capacity per camera,
  // sorted and de-duplicated by track id) at pose T_w_c; returns the slot.
  int add(const TrackedStereoFrame& frame, const SE3d& T_w_c);
  // Frees a slot (the caller removes the frame's landmarks and prior rows).
  void release(int slot);

  WindowFrame& operator[](int slot) { return frames_[static_cast<std::size_t>(slot)]; }
  const WindowFrame& operator[](int slot) const { return frames_[static_cast<std::size_t>(slot)]; }

  int numKeyframes() const;
  // The most recently added active frame, or -1.
  int newest() const;
  // The oldest keyframe, or -1 when fewer than two keyframes are in the window.
  int oldestKeyframe() const;
  // Active slots, oldest first (allocates: inspection only).
  std::vector<int> orderedSlots() const;

 private:
  std::array<WindowFrame, kMaxWindowFrames> frames_;
  std::int64_t sequence_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace voca::backend

namespace voca::backend {

// Matrices over the poses of every window slot (6 rows per slot; inactive slots stay zero).
inline constexpr int kWindowDim = 6 * kMaxWindowFrames;
using WindowMatrix = Eigen::Matrix<double, kWindowDim, kWindowDim>;
using WindowVector = Eigen::Matrix<double, kWindowDim, 1>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Pose increment convention of the window: translation added, rotation left-multiplied.
inline Vector6d poseDelta(const SE3d& T, const SE3d& T_lin) {
  Vector6d d;
  d.head<3>() = T.translation() - T_lin.translation();
  d.tail<3>() = (T.so3() * T_lin.so3().inverse()).log();
  return d;
}

inline void applyPoseIncrement(SE3d& T, const Vector6d& xi) {
  T.translation() += xi.head<3>();
  T.so3() = SO3d::exp(xi.tail<3>()) * T.so3();
}

}  // namespace voca::backend
