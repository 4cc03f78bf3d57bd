#pragma once
// Levenberg-Marquardt on the window: Huber-weighted reprojection residuals plus the
// marginalisation prior, every landmark eliminated by its own Schur complement (the reduced camera
// system is solved, landmarks are back-substituted), outlier filtering, and the pose-only step that
// places a new frame before the window is optimised.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "voca/backend/backend_config.h"
#include "voca/backend/landmark_store.h"
#include "voca/backend/marginalization_prior.h"
#include "voca/backend/stereo_residuals.h"
#include "voca/backend/window.h"

namespace voca::backend {

// References to the state the optimiser works on, which the estimator owns.
struct WindowStateRefs {
  Window& window;
  LandmarkStore& landmarks;
  MarginalizationPrior& prior;
};

// dst(i, j) += sign (A B^T)(i, j) for i >= j, dst a 6x6 block, A and B 6xK: the lower triangle of a
// symmetric block. The diagonal blocks of the reduced camera system (whose LDLT reads nothing else,
// so forming the upper half would add a third to the block products per landmark) and the host-host
// information of a frame pair (mirrored once per pair, not formed per residual). It goes in column
// pairs from the diagonal down, (0,1), (2,3), (4,5), so every column is whole SSE2 packets of two
// rows; the pairs also reach the three entries just above the diagonal (0,1), (2,3), (4,5), which
// are left changed. Eigen's packet product sums ((a0 b0 + a1 b1) + a2 b2) as the full block product
// does, so the entries are the same bit for bit. Always inlined: GCC would leave it a call in the Schur
// loop, once per landmark and frame.
enum class Accumulate { kAdd, kSubtract };
template <Accumulate kOp, typename Dst, typename Product>
[[gnu::always_inline]] inline void accumulate(Dst&& dst, const Product& product) {
  if constexpr (kOp == Accumulate::kAdd) {
    dst.noalias() += product;
  } else {
    dst.noalias() -= product;
  }
}
template <Accumulate kOp, typename DerivedA, typename DerivedB, typename Dst>
[[gnu::always_inline]] inline void accumulateLowerTriangle(const Eigen::MatrixBase<DerivedA>& A,
                                                           const Eigen::MatrixBase<DerivedB>& B, Dst&& dst) {
  static_assert(DerivedA::RowsAtCompileTime == 6 && DerivedB::RowsAtCompileTime == 6);
  accumulate<kOp>(dst.template block<6, 2>(0, 0), A * B.template topRows<2>().transpose());
  accumulate<kOp>(dst.template block<4, 2>(2, 2), A.template bottomRows<4>() * B.template middleRows<2>(2).transpose());
  accumulate<kOp>(dst.template block<2, 2>(4, 4), A.template bottomRows<2>() * B.template bottomRows<2>().transpose());
}

// dst -= A B^T for a 6x6 block dst of a column-major matrix (`stride` doubles from one column to the
// next) and A, B 6x3: the Schur loop's update of an off-diagonal block, over half of that loop's
// time. Where the CPU has AVX (checked once at run time; the build stays at the SSE2 baseline) four
// rows go in one register instead of two; elsewhere Eigen's product does it. Both compute every
// entry as dst - ((a0 b0 + a1 b1) + a2 b2), and the portable build fuses no multiply and add, so
// their bits are the same there (a VOCA_NATIVE build with FMA may round both differently).
void subtractProductTransposed(const Eigen::Matrix<double, 6, 3>& A, const Eigen::Matrix<double, 6, 3>& B, double* dst,
                               std::ptrdiff_t stride);

// One landmark's elimination from frame f's rows of the reduced camera system (the Schur loop, per
// landmark and frame): T_f = H_pl(f) H_ll^-1, which the off-diagonal blocks (f, g) take next;
// b_f -= T_f b_l; and the diagonal block (f, f) -= T_f H_pl(f)^T as accumulateLowerTriangle does
// it (lower triangle and the three entries just above the diagonal). `block_ff` is that block in a
// column-major matrix whose columns are `stride` doubles apart. AVX where the CPU has it, as
// subtractProductTransposed, with the same bits as Eigen's products in the portable build.
void eliminateLandmarkFromFrame(const Eigen::Matrix<double, 6, 3>& H_pl_f, const Eigen::Matrix3d& H_ll_inv,
                                const Eigen::Vector3d& b_l, Eigen::Matrix<double, 6, 3>& T_f, double* b_f,
                                double* block_ff, std::ptrdiff_t stride);

// Copies the strict lower triangle of a 6x6 matrix onto its upper one.
inline void mirrorLowerTriangle(Eigen::Matrix<double, 6, 6>& M) {
  for (int c = 1; c < 6; ++c) {
    for (int r = 0; r < c; ++r) M(r, c) = M(c, r);
  }
}

class WindowOptimizer {
 public:
  WindowOptimizer() = default;
  // All memory for max_landmarks is taken here.
  WindowOptimizer(const BackendConfig& config, const StereoResiduals& model);

  // The estimator's configuration and measurement model: the optimiser owns them (its loops read
  // them most) and the estimator reads them from here.
  const BackendConfig& config() const { return config_; }
  const StereoResiduals& model() const { return model_; }

  // Total cost: robust reprojection cost (an observation that cannot be projected counts like an
  // error of 10x the outlier threshold) plus the prior's.
  double cost(const WindowStateRefs& state) const;
  // The same total as the LM linearisation computes it along the way (what steps are judged by);
  // equals cost() exactly. Overwrites the optimiser's linearisation.
  double linearizedCost(const WindowStateRefs& state) { return linearize(state, nullptr, false); }
  // Up to max_iterations LM iterations; with `filter`, outliers are removed at filter_iteration (or
  // on convergence, whichever comes first). Returns the iterations run.
  int optimize(const WindowStateRefs& state, int max_iterations, bool filter);
  // Linearisations (passes over the residuals with Jacobians) of the last optimize(): most of its time.
  int linearizations() const { return linearizations_; }
  // Cost passes (residuals without Jacobians) of the last optimize(), each judging a step expected to
  // converge.
  int costPasses() const { return cost_passes_; }
  // Removes observations off by more than the outlier threshold; landmarks whose host view is an
  // outlier, that keep too few views or whose depth left the valid range die. Returns the number of
  // observations removed (those of dead landmarks included).
  int filterOutliers(const WindowStateRefs& state) const;
  // cost(), and with `outliers` (room for every live landmark) the filter's outlier bits of each
  // landmark by its position in alive(), from the same residuals: what optimize() does before its
  // filter, so that the filter needs no residual pass of its own.
  double cost(const WindowStateRefs& state, std::uint32_t* outliers) const;
  // filterOutliers, with the outlier bits from cost(state, outliers) at this same state when not null.
  int filterOutliers(const WindowStateRefs& state, const std::uint32_t* outliers) const;
  // Gauss-Newton on one frame's pose alone, landmarks and the other poses fixed. Returns the steps
  // taken (at most pose_only_iterations; fewer once a step is below the convergence bound).
  int optimizePose(const WindowStateRefs& state, int frame) const;

  // Marginalisation: the normal equations of the prior and the given landmarks' residuals, with
  // those landmarks eliminated. The result stays in hessian() and gradient() for the prior.
  void linearizeForMarginalization(const WindowStateRefs& state, const std::vector<int>& landmarks);
  WindowMatrix& hessian() { return H_; }
  const WindowVector& gradient() const { return b_; }
  WindowVector& gradient() { return b_; }

 private:
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  // Per-landmark linearisation, kept for the Schur complement and back-substitution. Its H_pl
  // blocks (pose-landmark) live packed in H_pl_, only for the frames the landmark touches: a pass
  // then streams through what it uses instead of a block for every window slot of every landmark.
  struct LandmarkLin {
    Eigen::Matrix3d H_ll;
    Eigen::Vector3d b_l;
    Eigen::Matrix3d H_ll_inv;  // damped
    std::uint32_t frames = 0;  // bit per frame slot with a non-zero H_pl
    int first_block = 0;       // its blocks in H_pl_: first_block + block[frame slot]
    std::array<std::uint8_t, kMaxWindowFrames> block{};
    double cost = 0.0;  // robust cost of the landmark's residuals at the linearisation point
    bool valid = false;
  };
  Mat63& H_pl(const LandmarkLin& L, int frame) {
    return H_pl_[static_cast<std::size_t>(L.first_block + L.block[static_cast<std::size_t>(frame)])];
  }

  // Normal equations of the residuals (all landmarks, or only_landmarks) plus the prior. Without
  // full_hessian, pose blocks above the diagonal are left out (what the LM solve reads). Returns the
  // total cost at this point, equal to cost() (same terms, same order): LM's acceptance test of a
  // step then needs no pass of its own when the next iteration linearises there anyway.
  double linearize(const WindowStateRefs& state, const std::vector<int>* only_landmarks, bool full_hessian);
  // Robust cost of one residual whose norm is e, or of one that cannot be projected.
  double residualCost(bool projected, double e) const;
  // The landmarks' costs summed in the one order cost() and linearize() share, plus the prior's.
  double totalCost(const WindowStateRefs& state, std::size_t count) const;
  // linearize() of the whole window, counted in linearizations_.
  double linearizeCounted(const WindowStateRefs& state);
  static void backup(const WindowStateRefs& state);
  static void restore(const WindowStateRefs& state);
  void applyIncrement(const WindowStateRefs& state, const WindowVector& dx);

  BackendConfig config_;
  StereoResiduals model_;
  std::vector<LandmarkLin> lin_;  // by position in the landmark list of the last linearize()
  std::vector<Mat63> H_pl_;
  int linearizations_ = 0;
  int cost_passes_ = 0;
  std::vector<std::uint32_t> outliers_;  // cost(state, outliers_.data()) before the filter
  // J_host^T W J_host and J_host^T W r summed per (host, target) frame pair, at host * slots + target;
  // valid where the host's bit mask in targets_of_host_ has the target.
  struct PairLin {
    Eigen::Matrix<double, 6, 6> H;
    Vector6d b;
  };
  std::array<PairLin, kMaxWindowFrames * kMaxWindowFrames> pairs_;
  std::array<std::uint32_t, kMaxWindowFrames> targets_of_host_{};
  // Work space (fixed size, so the solver never allocates).
  WindowMatrix H_, H_reduced_;
  WindowVector b_, b_reduced_, dx_;
  Eigen::LDLT<WindowMatrix> ldlt_;
};

}  // namespace voca::backend
