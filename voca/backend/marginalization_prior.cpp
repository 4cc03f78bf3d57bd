#include "voca/backend/marginalization_prior.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace voca::backend {

void MarginalizationPrior::clear() {
  H_.setZero();
  g_.setZero();
  c_ = 0.0;
}

void MarginalizationPrior::fixPose(int frame, double weight) {
  H_.block<6, 6>(6 * frame, 6 * frame) = weight * Eigen::Matrix<double, 6, 6>::Identity();
}

void MarginalizationPrior::removeFrame(int frame) {
  H_.middleRows<6>(6 * frame).setZero();
  H_.middleCols<6>(6 * frame).setZero();
  g_.segment<6>(6 * frame).setZero();
}

Vector6d MarginalizationPrior::delta(const Window& window, int frame) {
  const WindowFrame& f = window[frame];
  if (!f.active || !f.in_prior) return Vector6d::Zero();
  return poseDelta(f.T_w_c, f.T_w_c_lin);
}

double MarginalizationPrior::cost(const Window& window) const {
  WindowVector d = WindowVector::Zero();
  for (int i = 0; i < kMaxWindowFrames; ++i) d.segment<6>(6 * i) = delta(window, i);
  return 0.5 * d.dot(H_ * d) + g_.dot(d) + 0.5 * c_;
}

void MarginalizationPrior::addTo(const Window& window, WindowMatrix& H, WindowVector& b) const {
  WindowVector d = WindowVector::Zero();
  for (int f = 0; f < kMaxWindowFrames; ++f) d.segment<6>(6 * f) = delta(window, f);
  H += H_;
  b.noalias() += H_ * d;
  b += g_;
}

void MarginalizationPrior::eliminatePose(WindowMatrix& H, WindowVector& b, int frame) {
  const int o = 6 * frame;
  Eigen::Matrix<double, 6, 6> H_mm = H.block<6, 6>(o, o);
  H_mm.diagonal().array() += kTinyRegularization;
  const Eigen::Matrix<double, 6, 6> H_mm_inv = H_mm.ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
  const Eigen::Matrix<double, kWindowDim, 6> H_xm = H.middleCols<6>(o);
  const Vector6d b_m = b.segment<6>(o);
  H.noalias() -= H_xm * H_mm_inv * H_xm.transpose();
  b.noalias() -= H_xm * (H_mm_inv * b_m);
  H.middleRows<6>(o).setZero();
  H.middleCols<6>(o).setZero();
  b.segment<6>(o).setZero();
  H = 0.5 * (H + H.transpose()).eval();
}

void MarginalizationPrior::replace(Window& window, WindowMatrix& H, const WindowVector& b) {
  // Frames the prior now touches get their linearisation point fixed here (first estimates);
  // b is the gradient at the current state, so the prior's constant gradient is b - H delta0.
  WindowVector d = WindowVector::Zero();
  for (int f = 0; f < kMaxWindowFrames; ++f) {
    WindowFrame& fr = window[f];
    if (!fr.active) continue;
    if (!fr.in_prior && H.block<6, 6>(6 * f, 6 * f).diagonal().maxCoeff() > 0.0) {
      fr.in_prior = true;
      fr.T_w_c_lin = fr.T_w_c;
    }
    d.segment<6>(6 * f) = delta(window, f);
  }
  const WindowVector g = b - H * d;
  // Square-root form R = Lambda^1/2 V^T, r = Lambda^-1/2 V^T g from the eigendecomposition;
  // negative eigenvalues (round-off) are clipped, so the stored prior is symmetric PSD by construction.
  eigen_.compute(H);
  const auto& values = eigen_.eigenvalues();
  const auto& vectors = eigen_.eigenvectors();
  const double floor = std::max(values.maxCoeff(), 0.0) * 1e-14;
  WindowVector lambda_plus = WindowVector::Zero();
  WindowVector r = WindowVector::Zero();
  for (int k = 0; k < kWindowDim; ++k) {
    if (values(k) > floor && values(k) > 0.0) {
      lambda_plus(k) = values(k);
      r(k) = vectors.col(k).dot(g) / std::sqrt(values(k));
    }
  }
  // H = R^T R = V Lambda+ V^T; g = R^T r; c = r^T r.
  H_.noalias() = vectors * lambda_plus.asDiagonal() * vectors.transpose();
  H_ = 0.5 * (H_ + H_.transpose()).eval();
  g_.noalias() = vectors * (lambda_plus.array().sqrt().matrix().asDiagonal() * r);
  c_ = r.squaredNorm();
}

}  // namespace voca::backend
