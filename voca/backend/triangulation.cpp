#include "voca/backend/triangulation.h"

#include <Eigen/LU>

namespace voca::backend {

std::optional<Eigen::Vector3d> triangulateRays(const Eigen::Vector3d& o0, const Eigen::Vector3d& d0,
                                               const Eigen::Vector3d& o1, const Eigen::Vector3d& d1) {
  // Closest points of the rays o0 + t0 d0 and o1 + t1 d1: least squares in t0, t1.
  Eigen::Matrix<double, 3, 2> A;
  A.col(0) = d0;
  A.col(1) = -d1;
  const Eigen::Matrix2d AtA = A.transpose() * A;
  const double det = AtA.determinant();
  if (!(det > 1e-12)) return std::nullopt;  // parallel rays
  const Eigen::Vector2d t = AtA.inverse() * (A.transpose() * (o1 - o0));
  if (!(t(0) > 0.0 && t(1) > 0.0)) return std::nullopt;
  return Eigen::Vector3d(o0 + t(0) * d0);
}

int triangulateNewLandmarks(int frame, const Window& window, LandmarkStore& landmarks, const StereoResiduals& model,
                            const BackendConfig& config) {
  const WindowFrame& f = window[frame];
  const SE3d T_c_w = f.T_w_c.inverse();
  const WindowPoses poses = model.windowPoses(window);
  enum class Outcome { kCreated, kSkipped, kFull };
  // A track seen in this frame's camera ref_cam: triangulated against the view with the widest
  // baseline and stored, like every landmark, as a bearing and inverse distance from this frame's
  // left camera. A right-only track (the frontend's detection_nonoverlap) has no view there to
  // anchor it, so the bearing is a free parameter fixed by its views.
  const auto create = [&](const Observation& o, int ref_cam) {
    if (landmarks.full()) return Outcome::kFull;
    if (landmarks.find(o.id) >= 0) return Outcome::kSkipped;
    Eigen::Vector3d b_ref;
    if (!model.camera(ref_cam).unproject(o.px, b_ref)) return Outcome::kSkipped;
    const SE3d& T_c_ref = model.T_cam0_cam(ref_cam);
    // The other view with the widest baseline: another camera of this frame or any camera of
    // another frame in the window.
    double best_baseline = config.min_triangulation_dist_m;
    bool found = false;
    SE3d T_c_other;
    Eigen::Vector2d other_px;
    int other_cam = 0;
    for (int g = 0; g < kMaxWindowFrames; ++g) {
      const WindowFrame& fg = window[g];
      if (!fg.active) continue;
      for (int c = 0; c < 2; ++c) {
        if (g == frame && c == ref_cam) continue;
        const Observation* other = fg.find(c, o.id);
        if (other == nullptr) continue;
        const SE3d T = T_c_w * fg.T_w_c * model.T_cam0_cam(c);
        const double baseline = (T.translation() - T_c_ref.translation()).norm();
        if (baseline >= best_baseline) {
          best_baseline = baseline;
          found = true;
          T_c_other = T;
          other_px = other->px;
          other_cam = c;
        }
      }
    }
    if (!found) return Outcome::kSkipped;
    Eigen::Vector3d b_other;
    if (!model.camera(other_cam).unproject(other_px, b_other)) return Outcome::kSkipped;
    // All in this frame's left-camera coordinates.
    const std::optional<Eigen::Vector3d> p = triangulateRays(T_c_ref.translation(), T_c_ref.so3() * b_ref,
                                                             T_c_other.translation(), T_c_other.so3() * b_other);
    if (!p) return Outcome::kSkipped;
    const double rho = 1.0 / p->norm();
    if (!(rho >= config.min_inverse_distance && rho <= config.max_inverse_distance)) return Outcome::kSkipped;

    Landmark& lm = landmarks[landmarks.nextFree()];
    lm.id = o.id;
    lm.host = frame;
    lm.s = stereographicProject(*p);
    lm.rho = rho;
    lm.mask = 0;
    const HostBearing bearing(poses[static_cast<std::size_t>(frame)].T_w_c0, lm.s, false);
    // Every view of this track in the window, each checked against the triangulated point (the
    // left view that defines the bearing is exact by construction).
    for (int g = 0; g < kMaxWindowFrames; ++g) {
      const WindowFrame& fg = window[g];
      if (!fg.active) continue;
      for (int c = 0; c < 2; ++c) {
        const Observation* view = fg.find(c, o.id);
        if (view == nullptr) continue;
        lm.px[static_cast<std::size_t>(g)][static_cast<std::size_t>(c)] = view->px;
        Eigen::Vector2d r;
        if (g == frame && c == 0) {
          lm.mask |= 1u << maskBit(g, c);
        } else if (model.residual(poses, bearing, lm, g, c, r, nullptr) && r.norm() <= config.outlier_threshold_px) {
          lm.mask |= 1u << maskBit(g, c);
        }
      }
    }
    if (lm.numObs() < 2) return Outcome::kSkipped;
    if (!landmarks.add()) return Outcome::kFull;
    return Outcome::kCreated;
  };
  int created = 0;
  for (const Observation& o : f.obs[0]) {
    const Outcome outcome = create(o, 0);
    if (outcome == Outcome::kFull) return created;
    created += outcome == Outcome::kCreated;
  }
  for (const Observation& o : f.obs[1]) {
    if (f.find(0, o.id) != nullptr) continue;  // seen on the left: that view decides
    const Outcome outcome = create(o, 1);
    if (outcome == Outcome::kFull) return created;
    created += outcome == Outcome::kCreated;
  }
  return created;
}

}  // namespace voca::backend
