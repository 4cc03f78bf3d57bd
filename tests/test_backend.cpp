// Backend unit tests: the measurement model's Jacobians, the id map, and the estimator on synthetic
// observations with exact ground truth (noise-free, noisy, marginalisation prior, reset).

#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <unordered_map>

#include "voca/backend/estimator.h"
#include "voca/backend/id_map.h"
#include "voca/backend/reprojection.h"
#include "voca/backend/stereo_residuals.h"
#include "voca/backend/synthetic.h"
#include "voca/eval/metrics.h"
#include "voca/synth/rigs.h"

using namespace voca;

namespace {

// Products summed in the same order agree bit for bit on x86-64 without FMA (the shipped build).
// Where the compiler fuses multiply-adds (aarch64) two evaluation orders may round differently, by
// at most `fused`.
constexpr double productTolerance(double fused) {
#if defined(__x86_64__) && !defined(__FMA__)
  static_cast<void>(fused);
  return 0.0;
#else
  return fused;
#endif
}

SE3d randomPose(std::mt19937& rng, double translation_m) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Matrix<double, 6, 1> xi;
  for (int i = 0; i < 6; ++i) xi(i) = g(rng);
  xi.head<3>() *= translation_m;
  xi.tail<3>() *= 0.3;
  return SE3d::exp(xi);
}

// A landmark and two frames that see it: a random host pose, a target near it looking roughly the
// same way (farther along a fixed motion for later trials), a bearing near the optical axis and an
// inverse distance of 0.2-0.6 /m. Shared by the Jacobian tests so they draw the same configurations.
struct ViewConfig {
  SE3d T_w_h, T_w_t;
  Eigen::Vector2d s;
  double rho = 0.0;
};
ViewConfig randomViewConfig(std::mt19937& rng, int trial) {
  ViewConfig v;
  v.T_w_h = randomPose(rng, 1.0);
  v.T_w_t = v.T_w_h * SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.2, -0.1, 0.1, 0.05, -0.08, 0.03).finished() *
                                (0.5 + trial / 40.0));
  std::normal_distribution<double> g(0.0, 0.2);
  v.s = Eigen::Vector2d(g(rng), g(rng));
  v.rho = 0.2 + 0.1 * (trial % 5);
  return v;
}

// Calls check(camera, cam, T_cam0_cam, view) for 40 random views in each camera (cam 0 or 1) of the
// EuRoC (pinhole) and TUM-VI (fisheye) rigs.
template <typename Check>
void forEachRigCameraView(unsigned seed, Check&& check) {
  std::mt19937 rng(seed);
  const StereoRig euroc = synth::eurocRig();
  const StereoRig tumvi = synth::tumviRig();
  for (const StereoRig* rig : {&euroc, &tumvi}) {
    for (int cam = 0; cam < 2; ++cam) {
      const GenericCamera<double>& camera = rig->cameras[static_cast<std::size_t>(cam)].camera;
      const SE3d T_cam0_cam = cam == 0 ? SE3d() : rig->T_cam0_cam1();
      for (int trial = 0; trial < 40; ++trial) check(camera, cam, T_cam0_cam, randomViewConfig(rng, trial));
    }
  }
}

// Runs the estimator over a synthetic sequence; returns the body poses it output.
struct RunResult {
  std::vector<SE3d> T_world_body;
  int resets = 0, lost = 0, keyframes = 0;
  int longest_keyframe_gap = 0;  // most frames in a row without a keyframe
  int most_views_culled = 0;     // frames whose outlier cull removed over half of their views
  double max_prior_asymmetry = 0.0;
  double min_prior_eigenvalue = 0.0;
  double max_prior_eigenvalue = 0.0;
};

RunResult run(const StereoRig& rig, const SyntheticObservations& seq, const BackendConfig& config = {},
              bool check_prior = false) {
  VoEstimator estimator(config, rig);
  RunResult result;
  int since_keyframe = 0;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const TrackedStereoFrame& f = seq.frames[k];
    const PoseEstimate& e = estimator.process(f);
    result.T_world_body.push_back(e.T_world_body);
    result.resets += e.state == TrackingState::kReset;
    result.lost += e.state == TrackingState::kLost;
    result.keyframes += e.keyframe;
    since_keyframe = e.keyframe ? 0 : since_keyframe + 1;
    result.longest_keyframe_gap = std::max(result.longest_keyframe_gap, since_keyframe);
    const std::size_t views = f.observations[0].size() + f.observations[1].size();
    result.most_views_culled += 2 * static_cast<std::size_t>(e.num_outliers) > views;
    if (check_prior && k % 25 == 24) {
      const Eigen::MatrixXd H = estimator.priorHessian();
      const double scale = std::max(1.0, H.cwiseAbs().maxCoeff());
      result.max_prior_asymmetry =
          std::max(result.max_prior_asymmetry, (H - H.transpose()).cwiseAbs().maxCoeff() / scale);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (H + H.transpose()));
      result.min_prior_eigenvalue = std::min(result.min_prior_eigenvalue, eig.eigenvalues().minCoeff() / scale);
      result.max_prior_eigenvalue = std::max(result.max_prior_eigenvalue, eig.eigenvalues().maxCoeff());
    }
  }
  return result;
}

// Errors of the estimate against ground truth re-expressed with the first body pose as origin
// (the estimator starts at the identity body pose).
std::pair<double, double> maxPoseError(const std::vector<SE3d>& est, const std::vector<SE3d>& gt) {
  double max_t = 0.0, max_r = 0.0;
  const SE3d T_0_w = gt.front().inverse();
  for (std::size_t k = 0; k < est.size(); ++k) {
    const SE3d diff = (T_0_w * gt[k]).inverse() * est[k];
    max_t = std::max(max_t, diff.translation().norm());
    max_r = std::max(max_r, diff.so3().angle() * 180.0 / M_PI);
  }
  return {max_t, max_r};
}

// 4 s of exact observations with fast motion (about 10 keyframes): short enough for the emulated
// ARM run, long enough to marginalise.
SyntheticObservations shortNoiseFreeSequence(const StereoRig& rig) {
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.0;
  sc.duration_s = 4.0;
  sc.motion_scale = 2.5;
  return makeSyntheticObservations(rig, sc);
}

// 6 s of observations with 0.5 px noise: enough keyframes for the window to marginalise.
SyntheticObservations marginalisationSequence(const StereoRig& rig) {
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.5;
  sc.seed = 9;
  sc.duration_s = 6.0;
  return makeSyntheticObservations(rig, sc);
}

}  // namespace

TEST_CASE("backend: stereographic bearing round trip and Jacobian") {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int i = 0; i < 50; ++i) {
    Eigen::Vector3d d(g(rng), g(rng), std::abs(g(rng)) + 0.1);
    const Eigen::Vector2d s = stereographicProject(d);
    Eigen::Matrix<double, 3, 2> J;
    const Eigen::Vector3d b = stereographicUnproject(s, &J);
    CHECK((b - d.normalized()).norm() < 1e-12);
    for (int k = 0; k < 2; ++k) {
      const double h = 1e-6;
      Eigen::Vector2d sp = s, sm = s;
      sp(k) += h;
      sm(k) -= h;
      const Eigen::Vector3d num = (stereographicUnproject(sp) - stereographicUnproject(sm)) / (2 * h);
      // Central differences with h = 1e-6 are accurate to ~1e-9 on these O(1) functions.
      CHECK((num - J.col(k)).norm() < 1e-8);
    }
  }
}

TEST_CASE("backend: reprojection Jacobians match numerical ones for every camera model") {
  std::mt19937 rng(7);
  const StereoRig euroc = synth::eurocRig();
  const StereoRig tumvi = synth::tumviRig();
  std::vector<std::pair<GenericCamera<double>, SE3d>> cases = {
      {euroc.cameras[1].camera, euroc.T_cam0_cam1()},
      {tumvi.cameras[1].camera, tumvi.T_cam0_cam1()},
      {GenericCamera<double>::fromParams("ds", std::vector<double>{350, 350, 320, 240, -0.2, 0.6}), SE3d()},
      {GenericCamera<double>::fromParams("eucm", std::vector<double>{380, 380, 320, 240, 0.6, 1.1}), SE3d()},
  };
  int checked = 0;
  for (const auto& [camera, T_cam0_cam] : cases) {
    for (int trial = 0; trial < 40; ++trial) {
      const auto [T_w_h, T_w_t, s, rho] = randomViewConfig(rng, trial);
      Eigen::Vector2d uv;
      ReprojectionJacobians J;
      if (!reprojectLandmark(camera, T_w_h, T_w_t, T_cam0_cam, s, rho, uv, &J)) continue;
      const double h = 1e-6;
      // Central differences: truncation O(h^2 * f''') and rounding O(eps * |uv| / h) ~ 1e-7 px;
      // the tolerance is relative to the Jacobian's size (pixels per unit of increment).
      const auto close = [](const Eigen::Vector2d& num, const Eigen::Vector2d& ana) {
        return (num - ana).norm() <= 1e-5 * std::max(1.0, ana.norm());
      };
      for (int k = 0; k < 6; ++k) {
        Eigen::Matrix<double, 6, 1> xi = Eigen::Matrix<double, 6, 1>::Zero();
        xi(k) = h;
        const auto perturb = [](SE3d T, const Eigen::Matrix<double, 6, 1>& d) {
          T.translation() += d.head<3>();
          T.so3() = SO3d::exp(d.tail<3>()) * T.so3();
          return T;
        };
        Eigen::Vector2d up, um;
        REQUIRE(reprojectLandmark(camera, perturb(T_w_h, xi), T_w_t, T_cam0_cam, s, rho, up));
        REQUIRE(reprojectLandmark(camera, perturb(T_w_h, -xi), T_w_t, T_cam0_cam, s, rho, um));
        CHECK(close((up - um) / (2 * h), J.d_host.col(k)));
        REQUIRE(reprojectLandmark(camera, T_w_h, perturb(T_w_t, xi), T_cam0_cam, s, rho, up));
        REQUIRE(reprojectLandmark(camera, T_w_h, perturb(T_w_t, -xi), T_cam0_cam, s, rho, um));
        CHECK(close((up - um) / (2 * h), J.d_target.col(k)));
      }
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d(k) = h;
        Eigen::Vector2d up, um;
        REQUIRE(reprojectLandmark(camera, T_w_h, T_w_t, T_cam0_cam, s + d.head<2>(), rho + d(2), up));
        REQUIRE(reprojectLandmark(camera, T_w_h, T_w_t, T_cam0_cam, s - d.head<2>(), rho - d(2), um));
        CHECK(close((up - um) / (2 * h), J.d_landmark.col(k)));
      }
      ++checked;
    }
  }
  CHECK(checked > 100);  // most random configurations project in every model
}

TEST_CASE("backend: the target Jacobian is the host's times D, and host-frame residuals match the general model") {
  // WindowOptimizer::linearize sums J_host^T W J_host per frame pair and maps it to the target's
  // blocks with D (hostToTargetTransposed, timesHostToTarget); the landmark's own frame takes
  // reprojectInHost. Both must agree with the full model.
  int checked = 0;
  forEachRigCameraView(
      13, [&](const GenericCamera<double>& camera, int cam, const SE3d& T_cam0_cam, const ViewConfig& view) {
        const auto [T_w_h, T_w_t, s, rho] = view;
        Eigen::Vector2d uv;
        ReprojectionJacobians J;
        if (!reprojectLandmark(camera, T_w_h, T_w_t, T_cam0_cam, s, rho, uv, &J)) return;
        const Eigen::Vector3d dt = T_w_h.translation() - T_w_t.translation();
        // Sums of products of O(1e3) entries: rounding ~1e-12 relative.
        const double scale = std::max(1.0, J.d_host.norm() * J.d_host.norm());
        CHECK((timesHostToTarget<2>(dt, J.d_host) - J.d_target).norm() <= 1e-12 * std::max(1.0, J.d_target.norm()));
        const Eigen::Matrix<double, 6, 6> H_hh = J.d_host.transpose() * J.d_host;
        const Eigen::Matrix<double, 6, 6> H_tt = J.d_target.transpose() * J.d_target;
        const Eigen::Matrix<double, 6, 6> H_th = J.d_target.transpose() * J.d_host;
        const Eigen::Matrix<double, 6, 6> DtH = hostToTargetTransposed<6>(dt, H_hh);
        CHECK((DtH - H_th).norm() <= 1e-11 * scale);
        CHECK((timesHostToTarget<6>(dt, DtH) - H_tt).norm() <= 1e-11 * scale);
        const Eigen::Matrix<double, 6, 3> H_hl = J.d_host.transpose() * J.d_landmark;
        const Eigen::Matrix<double, 6, 3> H_tl = J.d_target.transpose() * J.d_landmark;
        CHECK((hostToTargetTransposed<3>(dt, H_hl) - H_tl).norm() <= 1e-11 * std::max(1.0, H_tl.norm()));

        // The same landmark seen from its own frame: reprojectInHost against the full model with
        // target = host, value and landmark Jacobian.
        Eigen::Vector2d uv_full, uv_host;
        ReprojectionJacobians J_full;
        if (!reprojectLandmark(camera, T_w_h, T_w_h, T_cam0_cam, s, rho, uv_full, &J_full)) return;
        const PoseMatrices host(T_w_h), cam0_cam(T_cam0_cam);
        const HostBearing bearing(host, s, true);
        const Eigen::Vector3d offset = cam0_cam.R_inv * cam0_cam.t;
        Eigen::Matrix<double, 2, 3> d_landmark = Eigen::Matrix<double, 2, 3>::Zero();
        REQUIRE(reprojectInHost(camera, cam0_cam.R_inv, offset, cam == 0, bearing, rho, uv_host, &d_landmark));
        // The full model rotates the bearing out of the host and back in: ~1e-15 relative in the point.
        CHECK((uv_host - uv_full).norm() <= 1e-9);
        CHECK((d_landmark - J_full.d_landmark).norm() <= 1e-8 * std::max(1.0, J_full.d_landmark.norm()));
        ++checked;
      });
  CHECK(checked > 100);
}

TEST_CASE("backend: the pose-only step's target Jacobian equals the full model's, bit for bit") {
  // WindowOptimizer::optimizePose asks for kTargetOnly with a bearing built without its derivative:
  // the residual and d_target must be exactly those of kHostAndTarget with the full bearing, in
  // other frames and in the landmark's own frame (which then takes the general model too).
  int checked = 0;
  forEachRigCameraView(
      29, [&](const GenericCamera<double>& camera, int, const SE3d& T_cam0_cam, const ViewConfig& view) {
        const auto [T_w_h, T_w_t, s, rho] = view;
        const PoseMatrices cam0_cam(T_cam0_cam);
        const Eigen::Vector3d offset = cam0_cam.R_inv * cam0_cam.t;
        const PoseMatrices host(T_w_h);
        for (const SE3d& T_w_target : {T_w_t, T_w_h}) {
          const PoseMatrices target(T_w_target);
          const Eigen::Matrix3d R_cam_w = cam0_cam.R_inv * target.R_inv;
          const TargetCamera target_camera{R_cam_w, target.t, offset};
          Eigen::Vector2d uv_full, uv_target;
          ReprojectionJacobians J_full, J_target;
          J_target.d_host.setConstant(7.0);
          J_target.d_landmark.setConstant(7.0);
          const bool full = reprojectLandmark(camera, host.t, HostBearing(host, s, true), target_camera, rho, uv_full,
                                              &J_full, PoseJacobians::kHostAndTarget);
          const bool only = reprojectLandmark(camera, host.t, HostBearing(host, s, false), target_camera, rho,
                                              uv_target, &J_target, PoseJacobians::kTargetOnly);
          REQUIRE(full == only);
          if (!full) continue;
          CHECK(uv_target == uv_full);
          CHECK(J_target.d_target == J_full.d_target);
          // Nothing else is written.
          CHECK((J_target.d_host.array() == 7.0).all());
          CHECK((J_target.d_landmark.array() == 7.0).all());
          ++checked;
        }
      });
  CHECK(checked > 200);
}

TEST_CASE("backend: a landmark's residuals computed together equal residual() one by one, bit for bit") {
  // linearize() and the cost pass take all of a landmark's residuals at once (two projections per
  // register on the fisheye rig); the pose-only step and the outlier filter still take them one by
  // one through residual(). Every decision compares these values, so they must be the same bits.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<std::uint32_t> any_mask(1u, (1u << (2 * kMaxWindowFrames)) - 1u);
  for (const StereoRig& rig : {synth::eurocRig(), synth::tumviRig()}) {
    const backend::StereoResiduals model(rig, 1.0, 1.0);
    backend::Window window(0);
    for (int f = 0; f < kMaxWindowFrames; ++f) {
      window[f].T_w_c = SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng),
                                   0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng))
                                      .finished());
    }
    const backend::WindowPoses poses = model.windowPoses(window);
    int valid_total = 0, invalid_total = 0;
    for (int trial = 0; trial < 400; ++trial) {
      backend::Landmark lm;
      lm.alive = true;
      lm.host = trial % kMaxWindowFrames;
      // Mostly in front of the cameras; some far off the axis or behind (which the pinhole cannot
      // project) and some not finite (which no camera can).
      lm.s = Eigen::Vector2d(u(rng), u(rng)) * (trial % 4 == 0 ? 2.0 : 0.4);
      lm.rho = trial % 40 == 7 ? std::numeric_limits<double>::quiet_NaN() : 0.1 + std::abs(u(rng));
      lm.mask = any_mask(rng);
      for (auto& frame : lm.px) {
        for (Eigen::Vector2d& px : frame) px = Eigen::Vector2d(300.0 + 200.0 * u(rng), 250.0 + 200.0 * u(rng));
      }
      for (const bool with_jacobians : {true, false}) {
        const HostBearing bearing(poses[static_cast<std::size_t>(lm.host)].T_w_c0, lm.s, with_jacobians);
        std::array<Eigen::Vector2d, 2 * kMaxWindowFrames> r;
        std::array<ReprojectionJacobians, 2 * kMaxWindowFrames> J;
        const std::uint32_t valid =
            model.landmarkResiduals(poses, bearing, lm, r.data(), with_jacobians ? J.data() : nullptr);
        REQUIRE((valid & ~lm.mask) == 0u);
        std::size_t i = 0;
        for (std::uint32_t m = lm.mask; m != 0; m &= m - 1, ++i) {
          const int bit = std::countr_zero(m);
          const int frame = bit / 2;
          Eigen::Vector2d r_one;
          ReprojectionJacobians J_one;
          const bool ok = model.residual(poses, bearing, lm, frame, bit % 2, r_one, with_jacobians ? &J_one : nullptr,
                                         frame != lm.host ? PoseJacobians::kHost : PoseJacobians::kNone);
          REQUIRE(((valid >> bit) & 1u) == static_cast<std::uint32_t>(ok));
          valid_total += ok;
          invalid_total += !ok;
          if (!ok) continue;
          CHECK(std::memcmp(r[i].data(), r_one.data(), sizeof(double) * 2) == 0);
          if (!with_jacobians) continue;
          CHECK(std::memcmp(J[i].d_landmark.data(), J_one.d_landmark.data(), sizeof(double) * 6) == 0);
          if (frame != lm.host) CHECK(std::memcmp(J[i].d_host.data(), J_one.d_host.data(), sizeof(double) * 12) == 0);
        }
      }
    }
    CHECK(valid_total > 1000);
    CHECK(invalid_total > 20);
  }
}

namespace {

// A Schur-loop block update on random values: A and B 6x3, the window matrix H, and the block at
// (row, col) that update(A, B, H) changes; `expected` is H with Eigen's full product subtracted there.
struct BlockUpdateCase {
  Eigen::Matrix<double, 6, 3> A, B;
  backend::WindowMatrix H, expected;
};
BlockUpdateCase randomBlockUpdateCase(std::mt19937& rng, int row, int col) {
  std::uniform_real_distribution<double> value(-1e3, 1e3);
  BlockUpdateCase c;
  for (int k = 0; k < 18; ++k) {
    c.A(k) = value(rng);
    c.B(k) = value(rng);
  }
  for (int k = 0; k < c.H.size(); ++k) c.H(k) = value(rng);
  c.expected = c.H;
  c.expected.block<6, 6>(row, col).noalias() -= c.A * c.B.transpose();
  return c;
}

// After a lower-triangle update of the diagonal block at (offset, offset), as accumulateLowerTriangle
// makes it: its lower triangle `matches` (value, expected) entry by entry; the column pairs also
// reach the entry above the diagonal in each pair, free to change (never read); everything else
// above the diagonal and outside the block equals `before`.
template <typename Matches>
void requireLowerTriangleUpdate(const backend::WindowMatrix& H, const backend::WindowMatrix& before,
                                const backend::WindowMatrix& expected, int offset, const Matches& matches) {
  for (int c = 0; c < backend::kWindowDim; ++c) {
    for (int r = 0; r < backend::kWindowDim; ++r) {
      const bool in_block = r >= offset && r < offset + 6 && c >= offset && c < offset + 6;
      const bool pair_upper = in_block && c == r + 1 && (r - offset) % 2 == 0;
      if (in_block && r >= c) {
        REQUIRE(matches(H(r, c), expected(r, c)));
      } else if (!pair_upper) {
        REQUIRE(H(r, c) == before(r, c));
      }
    }
  }
}

}  // namespace

TEST_CASE("backend: the Schur loop's off-diagonal block update equals Eigen's block product") {
  using backend::kWindowDim;
  // subtractProductTransposed takes AVX registers where the CPU has them: bit for bit on x86-64
  // without FMA (the shipped build), a few units in the last place with FMA (productTolerance).
  constexpr double kTolerance = productTolerance(1e-8);
  std::mt19937 rng(16);
  for (int trial = 0; trial < 50; ++trial) {
    const int row = 6 * (trial % kMaxWindowFrames), col = 6 * ((trial * 3 + 1) % kMaxWindowFrames);
    BlockUpdateCase u = randomBlockUpdateCase(rng, row, col);
    backend::subtractProductTransposed(u.A, u.B, &u.H(row, col), u.H.outerStride());
    for (int c = 0; c < kWindowDim; ++c) {
      for (int r = 0; r < kWindowDim; ++r) {
        const bool in_block = r >= row && r < row + 6 && c >= col && c < col + 6;
        if (in_block) {
          REQUIRE(std::abs(u.H(r, c) - u.expected(r, c)) <= kTolerance);
        } else {
          REQUIRE(u.H(r, c) == u.expected(r, c));
        }
      }
    }
  }
}

TEST_CASE("backend: the Schur loop's lower-triangle block update equals the full block product there") {
  using backend::WindowMatrix;
  // Bit for bit on x86-64 without FMA (the shipped build: the reduced system does not change by a
  // rounding). With FMA: a few units in the last place of terms up to 3e6 here, far below any
  // missing term.
  constexpr double kTolerance = productTolerance(1e-8);
  std::mt19937 rng(15);
  for (int trial = 0; trial < 50; ++trial) {
    const int offset = 6 * (trial % kMaxWindowFrames);
    BlockUpdateCase u = randomBlockUpdateCase(rng, offset, offset);
    const WindowMatrix before = u.H;
    backend::accumulateLowerTriangle<backend::Accumulate::kSubtract>(u.A, u.B, u.H.block<6, 6>(offset, offset));
    requireLowerTriangleUpdate(u.H, before, u.expected, offset,
                               [&](double value, double expected) { return std::abs(value - expected) <= kTolerance; });
  }
}

TEST_CASE("backend: one landmark's elimination from a frame's rows equals Eigen's products") {
  using backend::kWindowDim, backend::WindowMatrix, backend::WindowVector;
  // eliminateLandmarkFromFrame takes AVX where the CPU has it: bit for bit on x86-64 without FMA,
  // a few units in the last place (relative) with it.
  constexpr double kRelativeTolerance = productTolerance(1e-12);
  const auto near = [&](double value, double expected) {
    return std::abs(value - expected) <= kRelativeTolerance * (1.0 + std::abs(expected));
  };
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> value(-1e3, 1e3), inverse(-1e-2, 1e-2);
  for (int trial = 0; trial < 50; ++trial) {
    const int offset = 6 * (trial % kMaxWindowFrames);
    Eigen::Matrix<double, 6, 3> H_pl_f;
    Eigen::Matrix3d H_ll_inv;
    Eigen::Vector3d b_l;
    for (int k = 0; k < 18; ++k) H_pl_f(k) = value(rng);
    for (int k = 0; k < 9; ++k) H_ll_inv(k) = inverse(rng);
    for (int k = 0; k < 3; ++k) b_l(k) = value(rng);
    WindowMatrix H;
    WindowVector b;
    for (int k = 0; k < H.size(); ++k) H(k) = value(rng);
    for (int k = 0; k < b.size(); ++k) b(k) = value(rng);
    const WindowMatrix H_before = H;
    const WindowVector b_before = b;
    const Eigen::Matrix<double, 6, 3> T_expected = H_pl_f * H_ll_inv;
    WindowMatrix H_expected = H;
    H_expected.block<6, 6>(offset, offset).noalias() -= T_expected * H_pl_f.transpose();
    WindowVector b_expected = b;
    b_expected.segment<6>(offset).noalias() -= T_expected * b_l;

    Eigen::Matrix<double, 6, 3> T;
    backend::eliminateLandmarkFromFrame(H_pl_f, H_ll_inv, b_l, T, &b(offset), &H(offset, offset), H.outerStride());
    for (int k = 0; k < 18; ++k) REQUIRE(near(T(k), T_expected(k)));
    for (int r = 0; r < kWindowDim; ++r) {
      const bool in_block = r >= offset && r < offset + 6;
      if (in_block) {
        REQUIRE(near(b(r), b_expected(r)));
      } else {
        REQUIRE(b(r) == b_before(r));
      }
    }
    requireLowerTriangleUpdate(H, H_before, H_expected, offset, near);
  }
}

TEST_CASE("backend: a pair's host information from lower triangles and one mirror equals the full sum") {
  // linearize() forms J_host^T W J_host per residual in the lower triangle only and mirrors the sum
  // once per frame pair. The lower triangle is the full product's bit for bit (same two products per
  // entry, summed in the same order; see the Schur test for FMA builds), the upper half its mirror:
  // exactly symmetric, where the full product's upper half rounds (w a) b instead of (w b) a.
  // Roundings are bounded relative to the sum of the terms' magnitudes (a missing term is ~1e-6 of
  // it here).
  constexpr double kLowerRelative = productTolerance(1e-12);
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> value(-1e3, 1e3), weight(0.05, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Matrix<double, 6, 6> full = Eigen::Matrix<double, 6, 6>::Zero(), lower = full, magnitude = full;
    for (int residual = 0; residual < 1 + trial * 7; ++residual) {
      Eigen::Matrix<double, 2, 6> J;
      for (int k = 0; k < J.size(); ++k) J(k) = value(rng);
      const Eigen::Matrix<double, 6, 2> JW = weight(rng) * J.transpose();
      full.noalias() += JW * J;
      magnitude.noalias() += JW.cwiseAbs() * J.cwiseAbs();
      backend::accumulateLowerTriangle<backend::Accumulate::kAdd>(JW, J.transpose(), lower);
    }
    backend::mirrorLowerTriangle(lower);
    for (int c = 0; c < 6; ++c) {
      for (int r = c; r < 6; ++r) {
        REQUIRE(std::abs(lower(r, c) - full(r, c)) <= kLowerRelative * magnitude(r, c));
        REQUIRE(lower(c, r) == lower(r, c));
        // The full sum's upper half differs from its lower one by roundings only.
        CHECK(std::abs(full(c, r) - lower(c, r)) <= 1e-12 * magnitude(r, c));
      }
    }
  }
}

TEST_CASE("backend: the skew-matrix products from two terms per entry equal the products with hat(w)") {
  // Same two non-zero products summed per entry, so bit for bit where nothing fuses multiply-adds;
  // with FMA (aarch64) Eigen's product rounds one of them less: ~1e-16 relative to terms of 1e3.
  constexpr double kTolerance = productTolerance(1e-9);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> value(-1e3, 1e3);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d w(value(rng), value(rng), value(rng));
    const Eigen::Matrix3d W = SO3d::hat(w);
    Eigen::Matrix<double, 2, 3> A2;
    Eigen::Matrix<double, 6, 3> A6;
    Eigen::Matrix<double, 3, 6> X6;
    Eigen::Matrix<double, 3, 3> X3;
    Eigen::Vector3d x1;
    for (int k = 0; k < 6; ++k) A2(k) = value(rng);
    for (int k = 0; k < 18; ++k) {
      A6(k) = value(rng);
      X6(k) = value(rng);
    }
    for (int k = 0; k < 9; ++k) X3(k) = value(rng);
    for (int k = 0; k < 3; ++k) x1(k) = value(rng);
    CHECK((timesHat<2>(A2, w) - A2 * W).cwiseAbs().maxCoeff() <= kTolerance);
    CHECK((timesHat<6>(A6, w) - A6 * W).cwiseAbs().maxCoeff() <= kTolerance);
    // The negated forms as reprojectLandmark and hostToTargetTransposed use them.
    CHECK((-timesHat<2>(A2, w) - (-A2) * W).cwiseAbs().maxCoeff() <= kTolerance);
    CHECK((-hatTimes<6>(w, X6) - (-W) * X6).cwiseAbs().maxCoeff() <= kTolerance);
    CHECK((-hatTimes<3>(w, X3) - (-W) * X3).cwiseAbs().maxCoeff() <= kTolerance);
    CHECK((-hatTimes<1>(w, x1) - (-W) * x1).cwiseAbs().maxCoeff() <= kTolerance);
  }
}

TEST_CASE("backend: the outlier filter with the bits of a cost pass removes exactly what its own pass removes") {
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 2.0;  // about a third of the residuals beyond the 3 px threshold
  sc.seed = 7;
  sc.duration_s = 2.0;
  const SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  BackendConfig config;
  config.max_iterations = 2;
  VoEstimator a(config, rig), b(config, rig);
  int checked = 0;
  int filtered = 0;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    REQUIRE(a.process(seq.frames[k]).state != TrackingState::kLost);
    REQUIRE(b.process(seq.frames[k]).state != TrackingState::kLost);
    if (k < 10 || k % 5 != 0) continue;
    // LM without the filter moves the window away from the state process() filtered at.
    const double cost_before = a.optimizeWindow(3);
    REQUIRE(b.optimizeWindow(3) == cost_before);
    const int observations = a.filterWindowOutliers(true);
    CHECK(b.filterWindowOutliers(false) == observations);
    CHECK(a.numLandmarks() == b.numLandmarks());
    const double cost_after = a.optimizeWindow(0);
    CHECK(b.optimizeWindow(0) == cost_after);
    if (cost_after < cost_before) ++filtered;  // the filter removed something
    ++checked;
  }
  CHECK(checked >= 4);
  CHECK(filtered >= 1);
  const auto poses_a = a.windowPoses(), poses_b = b.windowPoses();
  REQUIRE(poses_a.size() == poses_b.size());
  for (std::size_t i = 0; i < poses_a.size(); ++i) {
    CHECK(poses_a[i].first == poses_b[i].first);
    CHECK(poses_a[i].second.matrix() == poses_b[i].second.matrix());
  }
}

TEST_CASE("backend: id map agrees with std::unordered_map under random inserts and erases") {
  IdSlotMap map(500);
  std::unordered_map<std::uint64_t, int> reference;
  std::mt19937_64 rng(11);
  for (int step = 0; step < 20000; ++step) {
    const std::uint64_t id = rng() % 2000;
    if (rng() % 3 == 0 || reference.size() >= 500) {
      map.erase(id);
      reference.erase(id);
    } else {
      const int slot = static_cast<int>(rng() % 1000);
      REQUIRE(map.insert(id, slot));
      reference[id] = slot;
    }
    if (step % 97 == 0) {
      for (std::uint64_t q = 0; q < 2000; ++q) {
        const auto it = reference.find(q);
        REQUIRE(map.find(q) == (it == reference.end() ? -1 : it->second));
      }
    }
  }
  CHECK(map.size() == reference.size());
}

// The emulated ARM run (tests/backend.cmake) leaves out the suite "long"; this short run keeps the
// estimator itself, keyframes and marginalisation included, checked on every architecture.
TEST_CASE("backend: noise-free observations over 4 s give the exact trajectory") {
  const StereoRig rig = synth::eurocRig();
  const SyntheticObservations seq = shortNoiseFreeSequence(rig);
  const RunResult result = run(rig, seq);
  CHECK(result.resets == 0);
  CHECK(result.lost == 0);
  CHECK(result.keyframes > 7);  // more than the window holds: marginalisation has happened
  const auto [max_t, max_r] = maxPoseError(result.T_world_body, seq.T_world_body);
  MESSAGE("noise-free 4 s: max error " << max_t * 1000 << " mm, " << max_r << " deg, " << result.keyframes
                                       << " keyframes");
  CHECK(max_t < 1e-3);  // the 30 s case's bounds
  CHECK(max_r < 0.01);
}

TEST_CASE("backend: a new frame that mostly disagrees with its pose guess keeps its views for the window to judge") {
  // Without a pose-only step every new frame starts at the constant-velocity guess, which on this
  // fast motion puts most of its views beyond the outlier threshold: a stand-in for a pose step that
  // did not converge (a blurred frame, a jerk the guess missed).
  const StereoRig rig = synth::eurocRig();
  const SyntheticObservations seq = shortNoiseFreeSequence(rig);
  for (const double share : {1.0, 0.5}) {
    BackendConfig config;
    config.pose_only_iterations = 0;
    config.max_frame_outlier_share = share;
    const RunResult r = run(rig, seq, config);
    const auto [max_t, max_r] = maxPoseError(r.T_world_body, seq.T_world_body);
    MESSAGE("share " << share << ": " << r.most_views_culled << " frames lost most views to the cull, " << r.lost
                     << " lost, " << r.resets << " resets, max error " << max_t * 1000 << " mm, " << max_r << " deg");
    if (share == 1.0) {
      // Basalt's cull: the frame keeps too few views and tracking breaks.
      CHECK(r.most_views_culled > 0);
      CHECK(r.resets > 0);
    } else {
      CHECK(r.most_views_culled == 0);
      CHECK(r.lost == 0);
      CHECK(r.resets == 0);
      CHECK(max_t < 1e-3);  // the bounds of the run with the pose-only step
      CHECK(max_r < 0.01);
    }
  }
}

TEST_CASE("backend: max_frames_after_kf bounds the gap between keyframes, and the trajectory stays exact") {
  const StereoRig rig = synth::eurocRig();
  const SyntheticObservations seq = shortNoiseFreeSequence(rig);
  for (const int max_gap : {0, 4}) {
    BackendConfig config;
    config.max_frames_after_kf = max_gap;
    const RunResult r = run(rig, seq, config);
    const auto [max_t, max_r] = maxPoseError(r.T_world_body, seq.T_world_body);
    MESSAGE("max_frames_after_kf " << max_gap << ": " << r.keyframes << " keyframes, longest run without one "
                                   << r.longest_keyframe_gap << " frames, max error " << max_t * 1000 << " mm");
    if (max_gap == 0) {
      CHECK(r.longest_keyframe_gap >= 4);  // the bound below is not met by chance
    } else {
      CHECK(r.longest_keyframe_gap < max_gap);
    }
    CHECK(max_t < 1e-3);
    CHECK(max_r < 0.01);
  }
}

TEST_CASE("backend: LM judges steps by the plain cost, and the window's cost never rises over iterations") {
  // LM judges each step by the cost that the next linearisation computes along the way: it must be
  // the plain cost pass (optimizeWindow(0)) to the bit, or a step that raises the true cost could
  // pass (a term left out: the prior, the residuals that cannot be projected; another set summed).
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 1.0;
  sc.seed = 5;
  sc.duration_s = 3.0;
  sc.motion_scale = 2.0;
  const SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  BackendConfig config;
  config.max_iterations = 2;  // leave the window short of its optimum after every frame
  VoEstimator estimator(config, rig);
  int checked = 0;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    REQUIRE(estimator.process(seq.frames[k]).state != TrackingState::kLost);
    if (k < 10 || k % 5 != 0) continue;
    double previous = estimator.optimizeWindow(0);
    CHECK(estimator.linearizedWindowCost() == previous);
    for (int round = 0; round < 4; ++round) {
      const double now = estimator.optimizeWindow(1);
      CHECK(now <= previous);
      previous = now;
    }
    ++checked;
  }
  CHECK(checked >= 8);
}

namespace {

// A 4 s sequence with 0.5 px noise (nothing beyond the 3 px outlier threshold) run with LM stopping at
// a 0.1 % decrease: every frame's estimate, and the true poses.
struct EarlyStoppingRun {
  std::vector<PoseEstimate> estimates;
  std::vector<SE3d> truth;
  int max_iterations = 0;
};
EarlyStoppingRun runEarlyStopping() {
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.5;
  sc.seed = 3;
  sc.duration_s = 4.0;
  const SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  BackendConfig config;
  config.converged_relative_decrease = 1e-3;
  VoEstimator estimator(config, rig);
  EarlyStoppingRun run{{}, seq.T_world_body, config.max_iterations};
  for (const TrackedStereoFrame& frame : seq.frames) {
    run.estimates.push_back(estimator.process(frame));
    REQUIRE(run.estimates.back().state != TrackingState::kLost);
  }
  return run;
}

// Stopping earlier must not cost accuracy: the estimates stay within 1 cm and 0.1 degree of the truth.
void checkEarlyStoppingAccuracy(const EarlyStoppingRun& run) {
  std::vector<SE3d> poses;
  for (const PoseEstimate& estimate : run.estimates) poses.push_back(estimate.T_world_body);
  const auto [max_t, max_r] = maxPoseError(poses, run.truth);
  CHECK(max_t < 0.01);
  CHECK(max_r < 0.1);
}

}  // namespace

TEST_CASE("backend: a step that LM expects to converge is judged by a cost pass, not by a linearisation") {
  // Converging early (here at a 0.1 % decrease), the loop ends or goes to the outlier filter after
  // the step: a linearisation to judge it by would go unused. Each iteration then costs one
  // linearisation; before, every early stop cost one more.
  const EarlyStoppingRun run = runEarlyStopping();
  int iterations = 0, linearizations = 0, early = 0;
  for (const PoseEstimate& estimate : run.estimates) {
    iterations += estimate.lm_iterations;
    linearizations += estimate.lm_linearizations;
    early += estimate.lm_iterations > 0 && estimate.lm_iterations < run.max_iterations;
  }
  MESSAGE(run.estimates.size() << " frames: " << iterations << " LM iterations, " << linearizations
                               << " linearisations, " << early << " frames stopped early");
  REQUIRE(early > static_cast<int>(run.estimates.size()) / 2);  // the case this is about
  CHECK(linearizations <= iterations);
}

TEST_CASE("backend: a cost pass judges only steps after which the loop stops") {
  // Each LM iteration is judged by one pass: a linearisation that the next iteration starts from, or,
  // when the quadratic model expects the step to converge, a cost pass. A step the model misjudges as
  // converging costs one pass more: the loop goes on and linearises the state just costed. Here no
  // observation is an outlier, so a frame takes its iterations' passes plus the linearisation it starts
  // from, and one more only for such a misjudged step (the actual decrease is 1.1-1.5 times the
  // model's, so a step just below the bound can still fail to converge). The model's decrease must
  // include the landmarks' own part: without it, it expected a small fraction of the actual decrease,
  // and most frames spent a pass on nothing (127 surplus passes in 79 frames; 13 with it).
  const EarlyStoppingRun run = runEarlyStopping();
  int frames = 0, surplus = 0, cost_passes = 0;
  for (const PoseEstimate& estimate : run.estimates) {
    if (estimate.lm_iterations == 0) continue;  // initialisation
    ++frames;
    cost_passes += estimate.lm_cost_passes;
    surplus += estimate.lm_linearizations + estimate.lm_cost_passes - estimate.lm_iterations - 1;
  }
  MESSAGE(frames << " optimised frames: " << cost_passes << " cost passes, " << surplus
                 << " passes beyond one per iteration and the first linearisation");
  REQUIRE(frames > 50);
  CHECK(cost_passes >= frames);  // every frame converges, and its last step is judged by a cost pass
  CHECK(surplus >= 0);
  CHECK(surplus * 4 < frames);
}

TEST_CASE("backend: an outlier filter that removes nothing ends the loop") {
  // Converging before filter_iteration, the loop runs the outlier filter and optimises the cleaned
  // problem. Here nothing is beyond the outlier threshold, so the problem after the filter is the one
  // that just converged: optimising it again would spend a linearisation on nothing. The loop
  // converges after its second step (one linearisation each; the step that converges is judged by a
  // cost pass), so a frame takes two or three linearisations, not three or four.
  const EarlyStoppingRun run = runEarlyStopping();
  int frames = 0, over_three = 0, linearizations = 0;
  for (const PoseEstimate& estimate : run.estimates) {
    if (estimate.lm_iterations == 0) continue;  // initialisation
    ++frames;
    linearizations += estimate.lm_linearizations;
    over_three += estimate.lm_linearizations > 3;
  }
  MESSAGE(frames << " optimised frames: " << linearizations << " linearisations, " << over_three
                 << " frames with more than three");
  REQUIRE(frames > 50);
  CHECK(over_three * 10 < frames);
  CHECK(linearizations < 3 * frames);
  checkEarlyStoppingAccuracy(run);
}

TEST_CASE("backend: the pose-only step ends once its step is below the convergence bound") {
  // Its Huber reweighting converges about tenfold per step; the steps that used to follow moved the
  // pose by micrometres, which the window optimisation after it refines anyway. Before the bound,
  // every frame took all pose_only_iterations steps.
  const EarlyStoppingRun run = runEarlyStopping();
  const int limit = BackendConfig{}.pose_only_iterations;
  int frames = 0, steps = 0, at_limit = 0;
  for (const PoseEstimate& estimate : run.estimates) {
    if (estimate.lm_iterations == 0) continue;  // initialisation
    ++frames;
    steps += estimate.pose_iterations;
    at_limit += estimate.pose_iterations == limit;
    REQUIRE(estimate.pose_iterations >= 1);
    REQUIRE(estimate.pose_iterations <= limit);
  }
  MESSAGE(frames << " optimised frames: " << steps << " pose-only steps, " << at_limit << " frames at the limit of "
                 << limit);
  REQUIRE(frames > 50);
  CHECK(at_limit * 10 < frames);
  CHECK(steps < (limit - 1) * frames);
  checkEarlyStoppingAccuracy(run);
}

TEST_CASE("backend: tracks seen only by the right camera become landmarks (the frontend's detection_nonoverlap)") {
  const StereoRig rig = synth::eurocRig();
  const SyntheticObservations seq = shortNoiseFreeSequence(rig);
  // Every third track loses its left views (right-only, as in a right camera's non-overlapping
  // area); the control drops those tracks altogether.
  SyntheticObservations right_only = seq, dropped = seq;
  const auto is_moved = [](const KeypointObservation& o) { return o.track_id % 3 == 0; };
  int moved_views = 0;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    std::erase_if(right_only.frames[k].observations[0], is_moved);
    std::erase_if(dropped.frames[k].observations[0], is_moved);
    moved_views += static_cast<int>(std::erase_if(dropped.frames[k].observations[1], is_moved));
  }
  REQUIRE(moved_views > 1000);
  const auto inliers = [&](const SyntheticObservations& s) {
    VoEstimator estimator({}, rig);
    long total = 0;
    std::vector<SE3d> poses;
    for (const TrackedStereoFrame& frame : s.frames) {
      const PoseEstimate& e = estimator.process(frame);
      CHECK(e.state != TrackingState::kReset);
      total += e.num_inliers;
      poses.push_back(e.T_world_body);
    }
    return std::pair{total, poses};
  };
  const auto [with_right_only, poses] = inliers(right_only);
  const auto [without, unused] = inliers(dropped);
  MESSAGE("inlier observations: " << with_right_only << " with right-only tracks, " << without << " without; "
                                  << moved_views << " right-only views offered");
  // Most right-only views end up attached to landmarks (a track needs two views with baseline
  // before it is triangulated, so not all of them).
  CHECK(with_right_only - without > moved_views / 2);
  const auto [max_t, max_r] = maxPoseError(poses, seq.T_world_body);
  CHECK(max_t < 1e-3);  // still exact: the right-only landmarks are consistent
  CHECK(max_r < 0.01);
}

TEST_CASE("backend: noise-free observations over 30 s give the exact trajectory" * doctest::test_suite("long")) {
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.0;
  const SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  const RunResult result = run(rig, seq);
  CHECK(result.resets == 0);
  CHECK(result.lost == 0);
  const auto [max_t, max_r] = maxPoseError(result.T_world_body, seq.T_world_body);
  MESSAGE("noise-free: max error " << max_t * 1000 << " mm, " << max_r << " deg over " << seq.frames.size()
                                   << " frames, " << result.keyframes << " keyframes");
  // The bound: exact data must come out exact up to the solver's convergence (observations
  // are stored as float, ~1e-4 px rounding, which alone is far below these bounds).
  CHECK(max_t < 1e-3);
  CHECK(max_r < 0.01);
}

TEST_CASE("backend: 0.5 px noise on a gentle trajectory keeps RTE (6 frames) below 0.5 cm" *
          doctest::test_suite("long")) {
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.5;
  sc.seed = 5;
  sc.duration_s = 15.0;  // 300 frames: enough for many marginalisations, quick under emulation
  const SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  const RunResult result = run(rig, seq, {}, true);
  CHECK(result.resets == 0);
  const RteResult rte = relativeTrajectoryError(result.T_world_body, seq.T_world_body, 6.0, DeltaUnit::kFrames);
  const AteResult ate = absoluteTrajectoryError(result.T_world_body, seq.T_world_body, AlignMode::kSe3);
  MESSAGE("0.5 px noise: RTE " << rte.stats.rmse * 100 << " cm, ATE " << ate.stats.rmse * 100 << " cm");
  CHECK(rte.stats.rmse < 0.005);
  // The marginalisation prior stays symmetric and positive semi-definite (relative to its scale,
  // round-off of the eigendecomposition is ~1e-15).
  CHECK(result.max_prior_eigenvalue > 0.0);
  CHECK(result.max_prior_asymmetry < 1e-12);
  CHECK(result.min_prior_eigenvalue > -1e-12);
}

TEST_CASE("backend: marginalising a keyframe gives the same optimum as keeping it (information moved, not lost)" *
          doctest::test_suite("long")) {
  const StereoRig rig = synth::eurocRig();
  const SyntheticObservations seq = marginalisationSequence(rig);
  // Two identical estimators (the estimator is deterministic). Plain least squares: with Huber
  // weights the prior keeps the weights of its linearisation point by design, which is not what
  // this test is about.
  BackendConfig config;
  config.obs_huber_thresh_px = 1e3;
  VoEstimator marginalized(config, rig), reference(config, rig);
  for (std::size_t k = 0; k < 80; ++k) {
    REQUIRE(marginalized.process(seq.frames[k]).state == TrackingState::kTracking);
    REQUIRE(reference.process(seq.frames[k]).state == TrackingState::kTracking);
  }
  REQUIRE(marginalized.numKeyframes() >= 4);
  marginalized.optimizeWindow(60);
  reference.optimizeWindow(60);
  const auto before = marginalized.windowPoses();
  // Remove the oldest keyframe into the prior in one, keep it (minus the views marginalisation has
  // to drop) in the other, and re-optimise both: the remaining poses must agree.
  REQUIRE(marginalized.marginalizeOldestKeyframe());
  REQUIRE(reference.dropViewsOfOldestKeyframe());
  marginalized.optimizeWindow(60);
  reference.optimizeWindow(60);
  const auto after = marginalized.windowPoses();
  const auto kept = reference.windowPoses();
  REQUIRE(after.size() + 1 == kept.size());
  REQUIRE(before.size() == kept.size());
  double max_diff_m = 0.0, max_diff_deg = 0.0, max_move_m = 0.0;
  for (std::size_t i = 0; i < after.size(); ++i) {
    REQUIRE(after[i].first == kept[i + 1].first);
    const SE3d& T = after[i].second;
    const SE3d& T_ref = kept[i + 1].second;
    max_diff_m = std::max(max_diff_m, (T.translation() - T_ref.translation()).norm());
    max_diff_deg = std::max(max_diff_deg, (T_ref.so3().inverse() * T.so3()).angle() * 180.0 / M_PI);
    max_move_m = std::max(max_move_m, (T.translation() - before[i + 1].second.translation()).norm());
  }
  MESSAGE("marginalised vs kept: " << max_diff_m * 1e6 << " um, " << max_diff_deg
                                   << " deg (the dropped views moved the window by " << max_move_m * 1e3 << " mm)");
  // The prior is the exact Schur complement at the linearisation point; what remains is the
  // nonlinearity of the millimetre-sized re-optimisation, measured at ~15 um. Losing the prior,
  // flipping its gradient's sign or halving its Hessian gives 1.5-3 mm (checked when writing this
  // test), so 50 um separates right from wrong with a wide margin on both sides.
  CHECK(max_diff_m < 5e-5);
  CHECK(max_diff_deg < 1e-3);
}

TEST_CASE("backend: a marginalised keyframe takes its landmarks along unless rehost_landmarks keeps the tracked ones" *
          doctest::test_suite("long")) {
  const StereoRig rig = synth::eurocRig();
  const SyntheticObservations seq = marginalisationSequence(rig);
  BackendConfig marginalise_config, rehost_config;
  rehost_config.rehost_landmarks = true;
  CHECK_FALSE(marginalise_config.rehost_landmarks);  // Basalt's behaviour is the default
  VoEstimator marginalise(marginalise_config, rig), rehost(rehost_config, rig);
  std::size_t frames = 0;
  // Up to the first marginalisation the two are the same estimator.
  while (marginalise.numKeyframes() < marginalise_config.max_keyframes && frames < seq.frames.size()) {
    REQUIRE(marginalise.process(seq.frames[frames]).state == TrackingState::kTracking);
    REQUIRE(rehost.process(seq.frames[frames]).state == TrackingState::kTracking);
    ++frames;
  }
  REQUIRE(marginalise.numKeyframes() == marginalise_config.max_keyframes);
  REQUIRE(marginalise.numLandmarks() == rehost.numLandmarks());
  const int landmarks = marginalise.numLandmarks();
  REQUIRE(marginalise.marginalizeOldestKeyframe());
  REQUIRE(rehost.marginalizeOldestKeyframe());
  const int lost_marginalising = landmarks - marginalise.numLandmarks();
  const int lost_rehosting = landmarks - rehost.numLandmarks();
  MESSAGE("landmarks leaving with the oldest keyframe: " << lost_marginalising << " marginalised, " << lost_rehosting
                                                         << " when re-hosting");
  // The oldest keyframe hosts landmarks the newest frame still tracks: marginalising takes them along
  // (their information goes into the prior), re-hosting keeps them in the window.
  CHECK(lost_marginalising > lost_rehosting);
  CHECK(lost_rehosting >= 0);
}

TEST_CASE("backend: a corrupted frame triggers a reported reset; the trajectory stays continuous and finite" *
          doctest::test_suite("long")) {
  const StereoRig rig = synth::eurocRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.3;
  sc.duration_s = 10.0;
  SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  // Frame 100: every left observation scrambled (a decoder glitch); all right ones dropped.
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(20.f, 700.f);
  for (KeypointObservation& o : seq.frames[100].observations[0]) o.px = Eigen::Vector2f(u(rng), u(rng) * 0.6f);
  seq.frames[100].observations[1].clear();
  // Frames 150-152: nothing tracked at all.
  for (std::size_t k = 150; k <= 152; ++k) seq.frames[k].clear();

  VoEstimator estimator({}, rig);
  std::vector<PoseEstimate> out;
  for (const TrackedStereoFrame& f : seq.frames) out.push_back(estimator.process(f));
  int resets = 0, lost = 0;
  for (const PoseEstimate& e : out) {
    REQUIRE(e.T_world_body.translation().allFinite());
    REQUIRE(e.T_world_body.unitQuaternion().coeffs().allFinite());
    resets += e.state == TrackingState::kReset;
    lost += e.state == TrackingState::kLost;
  }
  // Frame 100 fails and cannot restart (no right observations): lost; 101 restarts: reset.
  CHECK(out[100].state == TrackingState::kLost);
  CHECK(out[100].failure != FailureReason::kNone);
  CHECK(out[101].state == TrackingState::kReset);
  // The lost frame's message names its failure; the reset after it says that tracking started
  // again, where the failure field is kNone (it once read "reset (none)").
  CHECK(untrackedCause(out[100]) == failureReasonName(out[100].failure));
  CHECK(out[101].failure == FailureReason::kNone);
  CHECK(untrackedCause(out[101]) == "started again after lost frames");
  CHECK(out[150].state == TrackingState::kLost);
  CHECK(lost == 4);    // 100, 150, 151, 152
  CHECK(resets == 2);  // 101 and 153
  CHECK(out.back().state == TrackingState::kTracking);
  // Continuity: the failing frame repeats the last good pose, so there is no jump.
  CHECK((out[100].T_world_body.translation() - out[99].T_world_body.translation()).norm() < 1e-12);
  // Relative motion stays right after the resets (each reset only loses the motion of one frame,
  // ~1 cm here, which the 6-frame RTE sees at most in the pairs spanning it).
  std::vector<SE3d> est, gt;
  for (std::size_t k = 160; k < out.size(); ++k) {
    est.push_back(out[k].T_world_body);
    gt.push_back(seq.T_world_body[k]);
  }
  const RteResult rte = relativeTrajectoryError(est, gt, 6.0, DeltaUnit::kFrames);
  CHECK(rte.stats.rmse < 0.005);
}

TEST_CASE("backend: TUM-VI fisheye rig (kb4) with the shipped Gauss-Newton setting" * doctest::test_suite("long")) {
  const StereoRig rig = synth::tumviRig();
  SyntheticObservationsConfig sc;
  sc.noise_px = 0.5;
  sc.duration_s = 10.0;
  sc.seed = 3;
  const SyntheticObservations seq = makeSyntheticObservations(rig, sc);
  BackendConfig config;
  config.use_lm = false;  // configs/tumvi_vo.json, as the official TUM-VI file
  config.lm_lambda_initial = 1e-7;
  const RunResult result = run(rig, seq, config);
  CHECK(result.resets == 0);
  CHECK(result.lost == 0);
  const RteResult rte = relativeTrajectoryError(result.T_world_body, seq.T_world_body, 6.0, DeltaUnit::kFrames);
  MESSAGE("TUM-VI rig, Gauss-Newton, 0.5 px noise: RTE " << rte.stats.rmse * 100 << " cm");
  // TUM-VI's focal length is 190 px against EuRoC's 458 px, so 0.5 px is a 2.4x larger angle; the
  // EuRoC bound of 0.5 cm scaled by that would be 1.2 cm. Measured 0.44 cm (LM gives the same);
  // 0.8 cm still catches a broken fisheye path (Jacobians, unprojection), which gives centimetres.
  CHECK(rte.stats.rmse < 0.008);
}
