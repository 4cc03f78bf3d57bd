#pragma once
// The marginalisation prior: what marginalised keyframes and landmarks still say about the window's
// poses, as a square-root prior 1/2 |R delta + r|^2 around first-estimate linearisation points,
// stored expanded (H = R^T R, g = R^T r, c = r^T r).

#include <Eigen/Eigenvalues>

#include "voca/backend/window.h"

namespace voca::backend {

// Regularisation of blocks that are inverted without damping (marginalisation, landmark blocks); far
// below any real information (a 1 px error at 1 m gives about 1e5 on the pose diagonal).
inline constexpr double kTinyRegularization = 1e-9;

class MarginalizationPrior {
 public:
  // No information on any pose.
  void clear();
  // Fixes a pose with a strong isotropic prior (the gauge of VO: the first frame).
  void fixPose(int frame, double weight);
  // Forgets a window slot's rows and columns.
  void removeFrame(int frame);

  // delta of one slot from its linearisation point (zero unless the slot is in the prior).
  static Vector6d delta(const Window& window, int frame);
  double cost(const Window& window) const;
  // Adds the prior's Hessian and gradient at the current state to the normal equations H, b.
  void addTo(const Window& window, WindowMatrix& H, WindowVector& b) const;

  // Eliminates slot `frame` from the normal equations H, b (Schur complement on its pose); its rows
  // and columns are zero afterwards.
  static void eliminatePose(WindowMatrix& H, WindowVector& b, int frame);
  // Replaces the prior by the information H, b at the current state (the marginalised frame removed
  // from the window already): frames it now touches get their linearisation point fixed here.
  void replace(Window& window, WindowMatrix& H, const WindowVector& b);

  const WindowMatrix& hessian() const { return H_; }

 private:
  WindowMatrix H_;
  WindowVector g_;
  double c_ = 0.0;
  Eigen::SelfAdjointEigenSolver<WindowMatrix> eigen_;  // work space, so replace() does not allocate
};

}  // namespace voca::backend
