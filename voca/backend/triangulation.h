#pragma once
// Landmark creation: two-view triangulation of the tracks a new keyframe sees that no landmark
// holds yet, stored as a bearing and inverse distance from the keyframe's left camera.

#include <Eigen/Core>
#include <optional>

#include "voca/backend/backend_config.h"
#include "voca/backend/landmark_store.h"
#include "voca/backend/stereo_residuals.h"
#include "voca/backend/window.h"
#include "voca/geometry/se3.h"

namespace voca::backend {

// The midpoint-free two-ray triangulation: the point on ray 0 (origin o0, direction d0) closest to
// ray 1, all in one frame; nullopt for (near) parallel rays or a point behind either origin.
std::optional<Eigen::Vector3d> triangulateRays(const Eigen::Vector3d& o0, const Eigen::Vector3d& d0,
                                               const Eigen::Vector3d& o1, const Eigen::Vector3d& d1);

// Creates landmarks hosted in window slot `frame` for its tracks without one: each against the
// view with the widest baseline (at least min_triangulation_dist_m) in the window, kept when the
// inverse distance is in range and at least two views agree within the outlier threshold. Stops
// when the store is full. Returns the number created.
int triangulateNewLandmarks(int frame, const Window& window, LandmarkStore& landmarks, const StereoResiduals& model,
                            const BackendConfig& config);

}  // namespace voca::backend
