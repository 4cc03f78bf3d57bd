#include "voca/backend/window_optimizer.h"

#include <algorithm>
#include <bit>
#include <cmath>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define VOCA_AVX_BLOCK_PRODUCT 1
#else
#define VOCA_AVX_BLOCK_PRODUCT 0
#endif

namespace voca::backend {

namespace {

// A landmark whose outlier observations leave fewer than this many is dropped as a whole
// (Basalt's filterOutliers(threshold, 4)): with so few views the remaining ones are suspect too.
constexpr int kFilterMinObservations = 4;
// The pose step ends after a step shorter than this (metres and radians, as one norm). Its Huber
// reweighting converges about tenfold per iteration, so what is left after such a step is ~1e-6:
// a hundredth of a pixel at a 1000 px focal length and 1 m, and the window optimisation that
// follows refines the pose anyway. A tighter bound only adds iterations that move nothing.
constexpr double kPoseStepConvergedNorm = 1e-5;

#if VOCA_AVX_BLOCK_PRODUCT
// a0 c0 + a1 c1, then + a2 c2, per lane: how Eigen's packet product sums each entry of a 6x3 matrix
// (columns a0, a1, a2) times three coefficients. The AVX kernels below all sum through these, so
// their bits are Eigen's. Only the "avx" target: with "fma" GCC could fuse the multiplies and adds
// and change the bits.
[[gnu::target("avx"), gnu::always_inline]] inline __m256d combine(__m256d a0, __m256d a1, __m256d a2, double c0,
                                                                  double c1, double c2) {
  __m256d sum = _mm256_mul_pd(a0, _mm256_set1_pd(c0));
  sum = _mm256_add_pd(_mm256_mul_pd(a1, _mm256_set1_pd(c1)), sum);
  return _mm256_add_pd(_mm256_mul_pd(a2, _mm256_set1_pd(c2)), sum);
}
[[gnu::target("avx"), gnu::always_inline]] inline __m128d combine(__m128d a0, __m128d a1, __m128d a2, double c0,
                                                                  double c1, double c2) {
  __m128d sum = _mm_mul_pd(a0, _mm_set1_pd(c0));
  sum = _mm_add_pd(_mm_mul_pd(a1, _mm_set1_pd(c1)), sum);
  return _mm_add_pd(_mm_mul_pd(a2, _mm_set1_pd(c2)), sum);
}
// combine() of four rows (combineTwoRows: two) of a 6x3 column-major matrix, from the row at `a`.
[[gnu::target("avx"), gnu::always_inline]] inline __m256d combineFourRows(const double* a, double c0, double c1,
                                                                          double c2) {
  return combine(_mm256_loadu_pd(a), _mm256_loadu_pd(a + 6), _mm256_loadu_pd(a + 12), c0, c1, c2);
}
[[gnu::target("avx"), gnu::always_inline]] inline __m128d combineTwoRows(const double* a, double c0, double c1,
                                                                         double c2) {
  return combine(_mm_loadu_pd(a), _mm_loadu_pd(a + 6), _mm_loadu_pd(a + 12), c0, c1, c2);
}

// subtractProductTransposed on AVX: per column j of dst, the columns of A (rows 0-3 and 4-5) times
// B(j, k), combined, then subtracted. A's columns are loaded once, before the columns of dst: the
// compiler cannot hoist the loads itself, since dst could alias A.
[[gnu::target("avx")]] void subtractProductTransposedAvx(const Eigen::Matrix<double, 6, 3>& A,
                                                         const Eigen::Matrix<double, 6, 3>& B, double* dst,
                                                         std::ptrdiff_t stride) {
  const double* a = A.data();
  const __m256d a0 = _mm256_loadu_pd(a), a1 = _mm256_loadu_pd(a + 6), a2 = _mm256_loadu_pd(a + 12);
  const __m128d a0_low = _mm_loadu_pd(a + 4), a1_low = _mm_loadu_pd(a + 10), a2_low = _mm_loadu_pd(a + 16);
  for (int j = 0; j < 6; ++j) {
    double* column = dst + j * stride;
    const double b0 = B(j, 0), b1 = B(j, 1), b2 = B(j, 2);
    _mm256_storeu_pd(column, _mm256_sub_pd(_mm256_loadu_pd(column), combine(a0, a1, a2, b0, b1, b2)));
    _mm_storeu_pd(column + 4, _mm_sub_pd(_mm_loadu_pd(column + 4), combine(a0_low, a1_low, a2_low, b0, b1, b2)));
  }
}

// eliminateLandmarkFromFrame on AVX, the same operations per entry as the Eigen code below it.
[[gnu::target("avx")]] void eliminateLandmarkFromFrameAvx(const Eigen::Matrix<double, 6, 3>& H_pl_f,
                                                          const Eigen::Matrix3d& H_ll_inv, const Eigen::Vector3d& b_l,
                                                          Eigen::Matrix<double, 6, 3>& T_f, double* b_f,
                                                          double* block_ff, std::ptrdiff_t stride) {
  const double* h = H_pl_f.data();
  double* t = T_f.data();
  for (int j = 0; j < 3; ++j) {
    const double c0 = H_ll_inv(0, j), c1 = H_ll_inv(1, j), c2 = H_ll_inv(2, j);
    _mm256_storeu_pd(t + 6 * j, combineFourRows(h, c0, c1, c2));
    _mm_storeu_pd(t + 6 * j + 4, combineTwoRows(h + 4, c0, c1, c2));
  }
  _mm256_storeu_pd(b_f, _mm256_sub_pd(_mm256_loadu_pd(b_f), combineFourRows(t, b_l(0), b_l(1), b_l(2))));
  _mm_storeu_pd(b_f + 4, _mm_sub_pd(_mm_loadu_pd(b_f + 4), combineTwoRows(t + 4, b_l(0), b_l(1), b_l(2))));
  // The lower triangle in column pairs from the diagonal down, as accumulateLowerTriangle.
  for (int j = 0; j < 6; ++j) {
    double* column = block_ff + j * stride;
    const double c0 = h[j], c1 = h[j + 6], c2 = h[j + 12];
    const int first = j & ~1;
    if (first == 0) {
      _mm256_storeu_pd(column, _mm256_sub_pd(_mm256_loadu_pd(column), combineFourRows(t, c0, c1, c2)));
      _mm_storeu_pd(column + 4, _mm_sub_pd(_mm_loadu_pd(column + 4), combineTwoRows(t + 4, c0, c1, c2)));
    } else if (first == 2) {
      _mm256_storeu_pd(column + 2, _mm256_sub_pd(_mm256_loadu_pd(column + 2), combineFourRows(t + 2, c0, c1, c2)));
    } else {
      _mm_storeu_pd(column + 4, _mm_sub_pd(_mm_loadu_pd(column + 4), combineTwoRows(t + 4, c0, c1, c2)));
    }
  }
}

bool avxAvailable() {
  static const bool available = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx") != 0;  // also checks that the OS saves the wide registers
  }();
  return available;
}
#endif

}  // namespace

void subtractProductTransposed(const Eigen::Matrix<double, 6, 3>& A, const Eigen::Matrix<double, 6, 3>& B, double* dst,
                               std::ptrdiff_t stride) {
#if VOCA_AVX_BLOCK_PRODUCT
  if (avxAvailable()) {
    subtractProductTransposedAvx(A, B, dst, stride);
    return;
  }
#endif
  Eigen::Map<Eigen::Matrix<double, 6, 6>, 0, Eigen::OuterStride<>> block(dst, 6, 6, Eigen::OuterStride<>(stride));
  block.noalias() -= A * B.transpose();
}

void eliminateLandmarkFromFrame(const Eigen::Matrix<double, 6, 3>& H_pl_f, const Eigen::Matrix3d& H_ll_inv,
                                const Eigen::Vector3d& b_l, Eigen::Matrix<double, 6, 3>& T_f, double* b_f,
                                double* block_ff, std::ptrdiff_t stride) {
#if VOCA_AVX_BLOCK_PRODUCT
  if (avxAvailable()) {
    eliminateLandmarkFromFrameAvx(H_pl_f, H_ll_inv, b_l, T_f, b_f, block_ff, stride);
    return;
  }
#endif
  T_f.noalias() = H_pl_f * H_ll_inv;
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(b_f).noalias() -= T_f * b_l;
  accumulateLowerTriangle<Accumulate::kSubtract>(
      T_f, H_pl_f,
      Eigen::Map<Eigen::Matrix<double, 6, 6>, 0, Eigen::OuterStride<>>(block_ff, 6, 6, Eigen::OuterStride<>(stride)));
}

WindowOptimizer::WindowOptimizer(const BackendConfig& config, const StereoResiduals& model)
    : config_(config), model_(model) {
  lin_.resize(static_cast<std::size_t>(config_.max_landmarks));
  H_pl_.resize(static_cast<std::size_t>(config_.max_landmarks) * kMaxWindowFrames);
  outliers_.resize(static_cast<std::size_t>(config_.max_landmarks));
}

// ---- single-frame pose step ---------------------------------------------------------------------

// The passes over the residuals are [[gnu::flatten]]: GCC inlines neither reprojectLandmark nor the
// camera model's project() behind GenericCamera's std::visit on its own, and as calls they pass the
// Jacobians through memory for every residual, a large share of the backend's time. Same arithmetic
// in the same order, so the same values.
[[gnu::flatten]] int WindowOptimizer::optimizePose(const WindowStateRefs& state, int frame) const {
  const LandmarkStore& landmarks = state.landmarks;
  const std::uint32_t bits = frameBits(frame);
  WindowPoses poses = model_.windowPoses(state.window);
  for (int it = 0; it < config_.pose_only_iterations; ++it) {
    if (it > 0) poses = model_.windowPoses(state.window);
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Vector6d b = Vector6d::Zero();
    int count = 0;
    for (int k = static_cast<int>(landmarks.alive().size()) - 1; k >= 0; --k) {
      const Landmark& lm = landmarks[landmarks.alive()[static_cast<std::size_t>(k)]];
      if (!lm.alive || (lm.mask & bits) == 0) continue;
      // Only the frame's pose moves: no landmark Jacobian, so no bearing derivative either.
      const HostBearing bearing(poses[static_cast<std::size_t>(lm.host)].T_w_c0, lm.s, false);
      for (int c = 0; c < 2; ++c) {
        if ((lm.mask & (1u << maskBit(frame, c))) == 0) continue;
        Eigen::Vector2d r;
        ReprojectionJacobians J;
        if (!model_.residual(poses, bearing, lm, frame, c, r, &J, PoseJacobians::kTargetOnly)) continue;
        // Huber weights here too (Basalt's pose step ignores them, so one bad track can drag it).
        const double w = model_.weight(r.norm());
        // The LDLT below reads the lower triangle only.
        const Eigen::Matrix<double, 6, 2> JtW = w * J.d_target.transpose();
        accumulateLowerTriangle<Accumulate::kAdd>(JtW, J.d_target.transpose(), H);
        b.noalias() += JtW * r;
        ++count;
      }
    }
    if (count < 3) return it;
    H.diagonal().array() += 1e-6 * (1.0 + H.diagonal().array());
    const Vector6d dx = -H.ldlt().solve(b);
    if (!dx.allFinite()) return it;
    applyPoseIncrement(state.window[frame].T_w_c, dx);
    if (dx.norm() < kPoseStepConvergedNorm) return it + 1;
  }
  return config_.pose_only_iterations;
}

// ---- window optimisation ------------------------------------------------------------------------

double WindowOptimizer::residualCost(bool projected, double e) const {
  // An observation that cannot be projected counts like an error of 10x the outlier threshold, so
  // that a step moving points behind a camera is rejected.
  return model_.cost(projected ? e : 10.0 * config_.outlier_threshold_px);
}

double WindowOptimizer::totalCost(const WindowStateRefs& state, std::size_t count) const {
  double total = 0.0;
  for (std::size_t k = count; k-- > 0;) total += lin_[k].cost;
  return total + state.prior.cost(state.window);
}

double WindowOptimizer::cost(const WindowStateRefs& state) const { return cost(state, nullptr); }

[[gnu::flatten]] double WindowOptimizer::cost(const WindowStateRefs& state, std::uint32_t* outliers) const {
  const LandmarkStore& landmarks = state.landmarks;
  const WindowPoses poses = model_.windowPoses(state.window);
  double total = 0.0;
  // Per landmark, then over landmarks from the last: the order linearize() sums in (see totalCost).
  for (int k = static_cast<int>(landmarks.alive().size()) - 1; k >= 0; --k) {
    const Landmark& lm = landmarks[landmarks.alive()[static_cast<std::size_t>(k)]];
    if (!lm.alive) continue;
    const HostBearing bearing(poses[static_cast<std::size_t>(lm.host)].T_w_c0, lm.s, false);
    // Every residual first, then the sums in the same order, as in linearize().
    std::array<Eigen::Vector2d, 2 * kMaxWindowFrames> residuals;
    const std::uint32_t projected_bits = model_.landmarkResiduals(poses, bearing, lm, residuals.data(), nullptr);
    double landmark_cost = 0.0;
    std::uint32_t outlier_bits = 0;
    int count = 0;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1, ++count) {
      const int bit = std::countr_zero(m);
      const bool projected = (projected_bits & (1u << bit)) != 0;
      const double e = projected ? residuals[static_cast<std::size_t>(count)].norm() : 0.0;
      landmark_cost += residualCost(projected, e);
      // filterOutliers' test, on the same residual.
      if (!projected || e > config_.outlier_threshold_px) outlier_bits |= 1u << bit;
    }
    if (outliers != nullptr) outliers[k] = outlier_bits;
    total += landmark_cost;
  }
  return total + state.prior.cost(state.window);
}

using Matrix6d = Eigen::Matrix<double, 6, 6>;

[[gnu::flatten]] double WindowOptimizer::linearize(const WindowStateRefs& state, const std::vector<int>* only_landmarks,
                                                   bool full_hessian) {
  WindowMatrix& H = H_;
  WindowVector& b = b_;
  H.setZero();
  b.setZero();
  targets_of_host_.fill(0u);
  const std::vector<int>& list = only_landmarks != nullptr ? *only_landmarks : state.landmarks.alive();
  const WindowPoses poses = model_.windowPoses(state.window);
  int next_block = 0;
  for (std::size_t k = 0; k < list.size(); ++k) {
    const Landmark& lm = state.landmarks[list[k]];
    LandmarkLin& L = lin_[k];
    L.valid = false;
    L.cost = 0.0;
    if (!lm.alive) continue;
    L.H_ll.setZero();
    L.b_l.setZero();
    L.frames = 0;
    L.first_block = next_block;
    const int h = lm.host;
    const HostBearing bearing(poses[static_cast<std::size_t>(h)].T_w_c0, lm.s, true);
    // J_host^T W J_landmark per target frame: H_pl of the host is their sum, that of a target its
    // own times D^T (see hostToTargetTransposed; once per landmark and target, not per residual).
    std::array<Mat63, kMaxWindowFrames> host_pl;
    std::uint32_t targets = 0;
    // Every residual of the landmark first, then their sums in the same order: the projections are
    // independent of each other, and without the accumulation between them the CPU overlaps their
    // long dependency chains (divisions, the angle's rational function), two per register where the
    // camera model allows (StereoResiduals::landmarkResiduals).
    std::array<Eigen::Vector2d, 2 * kMaxWindowFrames> residuals;
    std::array<ReprojectionJacobians, 2 * kMaxWindowFrames> jacobians;
    const std::uint32_t valid = model_.landmarkResiduals(poses, bearing, lm, residuals.data(), jacobians.data());
    int count = 0;
    for (std::uint32_t m = lm.mask; m != 0; m &= m - 1, ++count) {
      const int bit = std::countr_zero(m);
      const int t = bit / 2;
      const Eigen::Vector2d& r = residuals[static_cast<std::size_t>(count)];
      const ReprojectionJacobians& J = jacobians[static_cast<std::size_t>(count)];
      if ((valid & (1u << bit)) == 0) {
        L.cost += residualCost(false, 0.0);
        continue;
      }
      const double e = r.norm();
      L.cost += residualCost(true, e);
      const double w = model_.weight(e);
      const Eigen::Matrix<double, 3, 2> JlW = w * J.d_landmark.transpose();
      L.H_ll.noalias() += JlW * J.d_landmark;
      L.b_l.noalias() += JlW * r;
      L.valid = true;
      if (t == h) continue;
      const Eigen::Matrix<double, 6, 2> JhW = w * J.d_host.transpose();
      PairLin& pair = pairs_[static_cast<std::size_t>(h * kMaxWindowFrames + t)];
      const std::uint32_t target_bit = 1u << t;
      if ((targets_of_host_[static_cast<std::size_t>(h)] & target_bit) == 0) {
        targets_of_host_[static_cast<std::size_t>(h)] |= target_bit;
        pair.H.setZero();
        pair.b.setZero();
      }
      // Symmetric: only the lower triangle per residual, mirrored once per pair below.
      accumulateLowerTriangle<Accumulate::kAdd>(JhW, J.d_host.transpose(), pair.H);
      pair.b.noalias() += JhW * r;
      if ((targets & target_bit) == 0) {
        targets |= target_bit;
        host_pl[static_cast<std::size_t>(t)].setZero();
      }
      host_pl[static_cast<std::size_t>(t)].noalias() += JhW * J.d_landmark;
    }
    if (targets != 0) {
      L.frames = targets | (1u << h);
      int blocks = 0;
      for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
        L.block[static_cast<std::size_t>(std::countr_zero(m))] = static_cast<std::uint8_t>(blocks++);
      }
      Mat63& pl_host = H_pl(L, h);
      pl_host.setZero();
      const Eigen::Vector3d& t_host = poses[static_cast<std::size_t>(h)].T_w_c0.t;
      for (std::uint32_t m = targets; m != 0; m &= m - 1) {
        const int t = std::countr_zero(m);
        const Mat63& X = host_pl[static_cast<std::size_t>(t)];
        pl_host += X;
        H_pl(L, t) = hostToTargetTransposed<3>(t_host - poses[static_cast<std::size_t>(t)].T_w_c0.t, X);
      }
      next_block += blocks;
    }
  }
  // Pose blocks from each (host, target) pair's J_host^T W J_host: host-host as is, target-target
  // D^T H D, target-host D^T H.
  for (int h = 0; h < kMaxWindowFrames; ++h) {
    const Eigen::Vector3d& t_host = poses[static_cast<std::size_t>(h)].T_w_c0.t;
    for (std::uint32_t m = targets_of_host_[static_cast<std::size_t>(h)]; m != 0; m &= m - 1) {
      const int t = std::countr_zero(m);
      PairLin& pair = pairs_[static_cast<std::size_t>(h * kMaxWindowFrames + t)];
      mirrorLowerTriangle(pair.H);
      const Eigen::Vector3d dt = t_host - poses[static_cast<std::size_t>(t)].T_w_c0.t;
      const Matrix6d DtH = hostToTargetTransposed<6>(dt, pair.H);
      H.block<6, 6>(6 * h, 6 * h) += pair.H;
      H.block<6, 6>(6 * t, 6 * t) += timesHostToTarget<6>(dt, DtH);
      // The LM solve reads only the lower triangle (LDLT<Lower>): the block above is skipped there.
      if (full_hessian || t > h) H.block<6, 6>(6 * t, 6 * h) += DtH;
      if (full_hessian || h > t) H.block<6, 6>(6 * h, 6 * t) += DtH.transpose();
      b.segment<6>(6 * h) += pair.b;
      b.segment<6>(6 * t) += hostToTargetTransposed<1>(dt, pair.b);
    }
  }
  state.prior.addTo(state.window, H, b);
  return totalCost(state, list.size());
}

void WindowOptimizer::backup(const WindowStateRefs& state) {
  for (int f = 0; f < kMaxWindowFrames; ++f) state.window[f].T_w_c_backup = state.window[f].T_w_c;
  for (const int i : state.landmarks.alive()) {
    Landmark& lm = state.landmarks[i];
    if (!lm.alive) continue;
    lm.s_backup = lm.s;
    lm.rho_backup = lm.rho;
  }
}

void WindowOptimizer::restore(const WindowStateRefs& state) {
  for (int f = 0; f < kMaxWindowFrames; ++f) state.window[f].T_w_c = state.window[f].T_w_c_backup;
  for (const int i : state.landmarks.alive()) {
    Landmark& lm = state.landmarks[i];
    if (!lm.alive) continue;
    lm.s = lm.s_backup;
    lm.rho = lm.rho_backup;
  }
}

void WindowOptimizer::applyIncrement(const WindowStateRefs& state, const WindowVector& dx) {
  for (int f = 0; f < kMaxWindowFrames; ++f) {
    if (state.window[f].active) applyPoseIncrement(state.window[f].T_w_c, dx.segment<6>(6 * f));
  }
  const std::vector<int>& alive = state.landmarks.alive();
  for (int k = static_cast<int>(alive.size()) - 1; k >= 0; --k) {
    Landmark& lm = state.landmarks[alive[static_cast<std::size_t>(k)]];
    const LandmarkLin& L = lin_[static_cast<std::size_t>(k)];
    if (!lm.alive || !L.valid) continue;
    Eigen::Vector3d rhs = L.b_l;
    for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
      const int f = std::countr_zero(m);
      rhs.noalias() += H_pl(L, f).transpose() * dx.segment<6>(6 * f);
    }
    const Eigen::Vector3d dl = -L.H_ll_inv * rhs;
    lm.s += dl.head<2>();
    lm.rho += dl(2);
  }
}

double WindowOptimizer::linearizeCounted(const WindowStateRefs& state) {
  ++linearizations_;
  return linearize(state, nullptr, false);
}

int WindowOptimizer::optimize(const WindowStateRefs& state, int max_iterations, bool filter) {
  linearizations_ = 0;
  cost_passes_ = 0;
  double lambda = config_.lm_lambda_initial;
  bool filtered = !filter;
  const std::vector<int>& alive = state.landmarks.alive();
  // lin_, H_ and b_ hold the linearisation at the current state, whose cost is `current`. An
  // accepted step is linearised right away when the next iteration starts there (no outlier filter
  // in between): that pass also gives the cost the step is judged by, so no separate cost pass runs.
  bool linearized = false;
  double current = 0.0;
  int it = 0;
  // Before the filter, a step judged by a cost pass also gives the filter's outlier bits at the state
  // it leaves (outliers_): the filter that follows needs no residual pass of its own.
  bool outliers_ready = false;
  std::uint32_t* const outliers = filtered ? nullptr : outliers_.data();
  for (; it < max_iterations; ++it) {
    if (!filtered && it >= config_.filter_iteration) {
      filterOutliers(state, outliers_ready ? outliers : nullptr);
      filtered = true;
      linearized = false;
    }
    if (!linearized) current = linearizeCounted(state);
    const bool next_iteration_here = it + 1 < max_iterations && (filtered || it + 1 < config_.filter_iteration);
    linearized = false;
    bool accepted = false;
    bool converged = false;
    outliers_ready = false;
    for (int attempt = 0; attempt < 8; ++attempt) {
      // Reduced camera system: damp, eliminate every landmark (Schur complement per landmark). Only
      // the lower triangle is formed: the LDLT reads nothing else, so the upper half would be
      // work thrown away.
      H_reduced_ = H_;
      b_reduced_ = b_;
      // sum_l b_l^T H_ll^-1 b_l: the landmarks' own share of the step's model decrease (below).
      double landmark_gradient_term = 0.0;
      for (int k = 0; k < kWindowDim; ++k) H_reduced_(k, k) += lambda * std::max(H_(k, k), 1e-6);
      for (int k = static_cast<int>(alive.size()) - 1; k >= 0; --k) {
        LandmarkLin& L = lin_[static_cast<std::size_t>(k)];
        // linearize() leaves dead landmarks invalid, so the landmark itself (a cache miss each) is not read.
        if (!L.valid) continue;
        Eigen::Matrix3d H_ll = L.H_ll;
        for (int d = 0; d < 3; ++d) H_ll(d, d) += lambda * std::max(L.H_ll(d, d), 1e-6) + kTinyRegularization;
        L.H_ll_inv = H_ll.inverse();
        if (!L.H_ll_inv.allFinite()) {
          L.valid = false;
          continue;
        }
        landmark_gradient_term += L.b_l.dot(L.H_ll_inv * L.b_l);
        for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
          const int f = std::countr_zero(m);
          Mat63 T_f;
          eliminateLandmarkFromFrame(H_pl(L, f), L.H_ll_inv, L.b_l, T_f, &b_reduced_(6 * f), &H_reduced_(6 * f, 6 * f),
                                     H_reduced_.outerStride());
          // Slots g < f: the bits of L.frames below f.
          const std::uint32_t lower = L.frames & ((1u << f) - 1u);
          for (std::uint32_t n = lower; n != 0; n &= n - 1) {
            const int g = std::countr_zero(n);
            subtractProductTransposed(T_f, H_pl(L, g), &H_reduced_(6 * f, 6 * g), H_reduced_.outerStride());
          }
        }
      }
      for (int f = 0; f < kMaxWindowFrames; ++f) {
        if (state.window[f].active) continue;
        H_reduced_.block<6, 6>(6 * f, 6 * f).setIdentity();
        b_reduced_.segment<6>(6 * f).setZero();
      }
      ldlt_.compute(H_reduced_);
      dx_ = ldlt_.solve(-b_reduced_);
      if (dx_.allFinite()) {
        // A step the quadratic model expects to lower the cost by less than the convergence bound
        // most likely ends the loop (or leads to the outlier filter, after which everything is
        // linearised anew): it is judged by a cost pass, not by a linearisation that would go
        // unused; any other step by the linearisation the next iteration starts from. Only the work
        // differs: both passes give the same cost to the bit, so every decision and result is the same.
        // The model's decrease for the whole step, poses and landmarks, is 0.5 (sum_l b_l^T H_ll^-1 b_l
        // - b_reduced.dx) (exactly, undamped). The landmarks' term is most of it (about 99 % on the
        // moving bench sequences): without it the model expected under a hundredth of the actual decrease (median), and
        // more than half of the cost passes judged steps after which the loop went on and linearised the
        // same state again.
        const double model_decrease = 0.5 * (landmark_gradient_term - b_reduced_.dot(dx_));
        const bool linearize_next =
            next_iteration_here && model_decrease > config_.converged_relative_decrease * current;
        backup(state);
        applyIncrement(state, dx_);
        cost_passes_ += !linearize_next;
        const double next = linearize_next ? linearizeCounted(state) : cost(state, outliers);
        if (std::isfinite(next) && next <= current) {
          accepted = true;
          outliers_ready = !linearize_next && !filtered;
          linearized = linearize_next;
          converged = current - next <= config_.converged_relative_decrease * current;
          current = next;
          if (config_.use_lm) lambda = std::max(config_.lm_lambda_min, lambda / 3.0);
          break;
        }
        restore(state);
        // The next attempt eliminates and back-substitutes with the linearisation of the restored
        // state, which the rejected step's pass overwrote (rare: almost every step is accepted).
        if (linearize_next) linearizeCounted(state);
      }
      if (!config_.use_lm || lambda >= config_.lm_lambda_max) break;
      lambda = std::min(config_.lm_lambda_max, lambda * 10.0);
    }
    if (!accepted || converged) {
      if (!filtered) {
        // Converged before the filter iteration: filter now and optimise the cleaned problem. When the
        // filter removed nothing, the problem is the one that just converged: done.
        const int removed = filterOutliers(state, outliers_ready ? outliers : nullptr);
        filtered = true;
        linearized = false;
        if (removed == 0) {
          ++it;
          break;
        }
        continue;
      }
      ++it;
      break;
    }
  }
  if (!filtered) filterOutliers(state, outliers_ready ? outliers : nullptr);
  return it;
}

int WindowOptimizer::filterOutliers(const WindowStateRefs& state) const { return filterOutliers(state, nullptr); }

[[gnu::flatten]] int WindowOptimizer::filterOutliers(const WindowStateRefs& state,
                                                     const std::uint32_t* precomputed) const {
  LandmarkStore& landmarks = state.landmarks;
  int removed = 0;
  const WindowPoses poses = model_.windowPoses(state.window);
  for (int k = static_cast<int>(landmarks.alive().size()) - 1; k >= 0; --k) {
    const int i = landmarks.alive()[static_cast<std::size_t>(k)];
    Landmark& lm = landmarks[i];
    if (!lm.alive) continue;
    const int observations = lm.numObs();
    if (!(lm.rho > 0.0 && lm.rho <= 2.0 * config_.max_inverse_distance) || !lm.s.allFinite()) {
      removed += observations;
      landmarks.remove(i);
      continue;
    }
    // Removing a landmark moves the last one of alive() to its position, one already visited: the
    // positions still to come keep their landmarks (and their precomputed bits).
    std::uint32_t outliers = precomputed != nullptr ? precomputed[k] : 0u;
    const HostBearing bearing(poses[static_cast<std::size_t>(lm.host)].T_w_c0, lm.s, false);
    for (std::uint32_t m = precomputed != nullptr ? 0u : lm.mask; m != 0; m &= m - 1) {
      const int bit = std::countr_zero(m);
      Eigen::Vector2d r;
      if (!model_.residual(poses, bearing, lm, bit / 2, bit % 2, r, nullptr) ||
          r.norm() > config_.outlier_threshold_px) {
        outliers |= 1u << bit;
      }
    }
    if (outliers == 0) continue;
    const bool host_outlier = (outliers & (1u << maskBit(lm.host, 0))) != 0;
    if (host_outlier || observations - std::popcount(outliers) < kFilterMinObservations) {
      removed += observations;
      landmarks.remove(i);
    } else {
      removed += std::popcount(outliers & lm.mask);
      lm.mask &= ~outliers;
    }
  }
  return removed;
}

// ---- marginalisation ----------------------------------------------------------------------------

void WindowOptimizer::linearizeForMarginalization(const WindowStateRefs& state, const std::vector<int>& landmarks) {
  // Information on the window from the prior and the marginalised landmarks, landmarks eliminated.
  linearize(state, &landmarks, true);
  for (std::size_t k = 0; k < landmarks.size(); ++k) {
    const LandmarkLin& L = lin_[k];
    if (!L.valid) continue;
    const Eigen::Matrix3d H_ll_inv = (L.H_ll + kTinyRegularization * Eigen::Matrix3d::Identity()).inverse();
    if (!H_ll_inv.allFinite()) continue;
    for (std::uint32_t m = L.frames; m != 0; m &= m - 1) {
      const int f = std::countr_zero(m);
      const Mat63 T = H_pl(L, f) * H_ll_inv;
      b_.segment<6>(6 * f).noalias() -= T * L.b_l;
      for (std::uint32_t n = L.frames; n != 0; n &= n - 1) {
        const int g = std::countr_zero(n);
        H_.block<6, 6>(6 * f, 6 * g).noalias() -= T * H_pl(L, g).transpose();
      }
    }
  }
}

}  // namespace voca::backend
