#include "pipeline/synth/synth_runner.h"

#include <fmt/core.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <span>
#include <thread>
#include <vector>

#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "formats/trajectory/trajectory_io.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"
#include "voca/synth/renderer.h"
#include "voca/synth/rigs.h"
#include "voca/synth/scene.h"

namespace voca::pipeline {

namespace {

namespace fs = std::filesystem;
using namespace voca::synth;

// Sequences start at 1 s rather than 0 so that no tool mistakes the first timestamp for "unset".
constexpr int64_t kStartNs = 1'000'000'000;
// Minimum distance from the camera path to the walls (the task's requirement) and to objects.
constexpr double kWallClearanceM = 0.5;
constexpr double kObjectClearanceM = 0.5;

// A name that can only mean a file: not found is the answer to give, not the list of presets.
bool looksLikePath(const std::string& camera) {
  const std::string extension = fs::path(camera).extension().string();
  return camera.find('/') != std::string::npos || extension == ".json" || extension == ".yaml" || extension == ".yml" ||
         extension == ".txt";
}

StereoRig loadRig(const std::string& camera) {
  if (std::optional<StereoRig> rig = builtinRig(camera)) return *rig;
  if (!fs::exists(camera)) {
    if (looksLikePath(camera)) throw InputError("--camera " + camera + ": calibration file or folder not found");
    throw InputError("--camera '" + camera +
                     "': expected 'euroc', 'tumvi' or a calibration file/folder (Basalt .json, Kalibr .yaml, "
                     "EuRoC mav0, KITTI calib.txt)");
  }
  StereoRig rig = loadCalibration(camera);
  rig.requireStereo();
  rig.cameras.resize(2);
  for (const CameraCalibration& c : rig.cameras) {
    if (c.width <= 0 || c.height <= 0) throw InputError(camera + ": camera resolution missing or invalid");
  }
  return rig;
}

// Largest distance from the body origin to any camera: the clearance the body path needs on top
// of the cameras' own.
double rigRadius(const StereoRig& rig) {
  double radius = 0.0;
  for (const CameraCalibration& c : rig.cameras) radius = std::max(radius, c.T_body_cam.translation().norm());
  return radius;
}

struct Sequence {
  std::vector<int64_t> t_ns;
  std::vector<SE3d> T_world_body;
  RoomBox room;
  // The body pose at any time (for exposure sampling between frames), clamped to the covered span.
  std::function<SE3d(int64_t t_ns)> body_pose_at;
};

// The longest sequence synth renders (stereo frames): 13.9 h at 20 Hz, about 0.5 TB of PNGs.
constexpr int kMaxFrames = 1'000'000;

// With --trajectory: the frames --seconds asks for; -1 = the whole file.
int64_t trajectoryFrameLimit(const SynthOptions& options) {
  return options.seconds ? static_cast<int64_t>(std::llround(*options.seconds * options.rate_hz)) : -1;
}

Sequence presetSequence(const SynthOptions& options, const StereoRig& rig) {
  const std::optional<MotionPreset> preset = parseMotionPreset(options.motion);
  if (!preset) {
    throw InputError("--motion '" + options.motion + "': expected gentle, fast-rotation or aggressive");
  }
  Sequence seq;
  const double seconds = options.seconds.value_or(20.0);
  const int frames = static_cast<int>(std::floor(seconds * options.rate_hz + 1e-9));
  const SE3d T_cam0_body = rig.cameras[0].T_body_cam.inverse();
  // The preset moves cam0; every camera and the body must keep the clearance.
  const double clearance = kWallClearanceM + 2.0 * rigRadius(rig) + 0.05;
  const RoomBox room = seq.room;
  seq.body_pose_at = [preset = *preset, room, clearance, T_cam0_body](int64_t t_ns) {
    const double t = static_cast<double>(t_ns - kStartNs) * 1e-9;
    return presetCameraPose(preset, t, room, clearance) * T_cam0_body;
  };
  for (int k = 0; k < frames; ++k) {
    const double t = static_cast<double>(k) / options.rate_hz;
    seq.t_ns.push_back(kStartNs + static_cast<int64_t>(std::llround(t * 1e9)));
    seq.T_world_body.push_back(presetCameraPose(*preset, t, seq.room, clearance) * T_cam0_body);
  }
  return seq;
}

Sequence fileSequence(const SynthOptions& options, const StereoRig& rig) {
  const Trajectory trajectory = loadTrajectory(options.trajectory);
  if (trajectory.poses.size() < 2) throw InputError(options.trajectory.string() + ": needs at least two poses");
  if (!trajectory.has_timestamps) {
    throw InputError(options.trajectory.string() +
                     ": KITTI poses without times; give a trajectory with timestamps (TUM or EuRoC csv)");
  }
  Sequence seq;
  const int64_t t0 = trajectory.poses.front().t_ns + static_cast<int64_t>(std::llround(options.start_s * 1e9));
  const int64_t t1 = trajectory.poses.back().t_ns;
  if (t0 >= t1) {
    throw InputError(fmt::format("--start {} s: beyond the end of {} ({:.1f} s long)", options.start_s,
                                 options.trajectory.string(),
                                 static_cast<double>(t1 - trajectory.poses.front().t_ns) * 1e-9));
  }
  const double period_ns = 1e9 / options.rate_hz;
  const int64_t limit = trajectoryFrameLimit(options);
  for (int64_t k = 0;; ++k) {
    if (limit >= 0 && k >= limit) break;
    const int64_t t = t0 + static_cast<int64_t>(std::llround(static_cast<double>(k) * period_ns));
    if (t > t1) break;
    const std::optional<SE3d> pose = interpolatePose(trajectory, t);
    if (!pose) break;
    seq.t_ns.push_back(t);
    seq.T_world_body.push_back(*pose);
  }
  if (seq.t_ns.size() < 2) {
    throw InputError(options.trajectory.string() + ": covers less than two frames at " +
                     fmt::format("{}", options.rate_hz) + " Hz");
  }
  std::vector<Eigen::Vector3d> positions;
  for (const SE3d& T : seq.T_world_body) positions.push_back(T.translation());
  const RoomPlacement placement = placeInRoom(positions, RoomBox(), kWallClearanceM + rigRadius(rig) + 0.05);
  seq.room = placement.room;
  for (SE3d& T : seq.T_world_body) T.translation() += placement.offset;
  seq.body_pose_at = [trajectory, offset = placement.offset, t0, t1](int64_t t_ns) {
    SE3d T = *interpolatePose(trajectory, std::clamp(t_ns, t0, t1));
    T.translation() += offset;
    return T;
  };
  return seq;
}

// Renders one camera image with `threads` workers pulling row blocks from a shared counter; the
// renderer makes every pixel independent of the split, so the bytes do not depend on it.
void renderImage(const Scene& scene, const RayTable& rays, std::span<const SE3d> exposure_poses,
                 const RenderSettings& settings, GrayImage& image, int threads) {
  constexpr int kBlockRows = 40;
  image.resize(rays.width(), rays.height());
  const ImageView<std::uint8_t> view = image.view();
  std::atomic<int> next{0};
  auto work = [&] {
    for (;;) {
      const int y0 = next.fetch_add(kBlockRows);
      if (y0 >= rays.height()) return;
      renderRows(scene, rays, exposure_poses, settings, view, y0, std::min(y0 + kBlockRows, rays.height()));
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

}  // namespace

SynthResult synthesizeSequence(const SynthOptions& options) {
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 1000.0)) throw InputError("--rate: expected 0 < Hz <= 1000");
  for (const char* camera : {"cam0", "cam1"}) {
    // A rendering writes images and data.csv beside the videos, which would leave a folder of neither.
    const fs::path video = options.out / "mav0" / camera / "data.mp4";
    if (fs::exists(video)) {
      throw InputError(fmt::format("{} holds a video dataset ({}); voca synth writes images: choose another folder",
                                   options.out.string(), video.string()));
    }
  }
  if (options.seconds && !(*options.seconds > 0.0)) throw InputError("--seconds: expected a positive number");
  // A bound before anything is allocated per frame: poses are kept for the whole sequence.
  if (options.seconds && *options.seconds * options.rate_hz > kMaxFrames) {
    throw InputError(fmt::format("--seconds {}: {:.0f} frames at {} Hz; at most {} frames ({:.1f} h at this rate)",
                                 *options.seconds, *options.seconds * options.rate_hz, options.rate_hz, kMaxFrames,
                                 kMaxFrames / options.rate_hz / 3600.0));
  }
  if (!(options.noise_sigma >= 0.0)) throw InputError("--noise-sigma: expected >= 0");
  if (!(options.psf_sigma_px >= 0.0 && options.psf_sigma_px <= 5.0)) {
    throw InputError("--psf-sigma: expected 0 to 5 px");
  }
  if (options.supersample < 1 || options.supersample > 8) throw InputError("--supersample: expected 1..8");
  if (options.threads < 1) throw InputError("--threads: expected >= 1");
  if (!(options.exposure_ms >= 0.0 && options.exposure_ms * options.rate_hz <= 1000.0)) {
    throw InputError("--exposure: expected 0 ms up to one frame period");
  }
  if (!(options.gain > 0.0 && options.gain <= 4.0)) throw InputError("--gain: expected 0 < gain <= 4");
  if (!(options.start_s >= 0.0)) throw InputError("--start: expected >= 0 s");
  if (options.start_s > 0.0 && options.trajectory.empty()) {
    throw InputError("--start: only with --trajectory (presets start at their beginning)");
  }

  const auto start = std::chrono::steady_clock::now();
  const StereoRig rig = loadRig(options.camera);
  // What `voca run` requires of every input (a frame slot holds both images at one size).
  if (rig.cameras[0].width != rig.cameras[1].width || rig.cameras[0].height != rig.cameras[1].height) {
    throw InputError(fmt::format("--camera {}: cam0 is {}x{} but cam1 {}x{}; the VO needs both cameras at one size",
                                 options.camera, rig.cameras[0].width, rig.cameras[0].height, rig.cameras[1].width,
                                 rig.cameras[1].height));
  }
  const Sequence seq = options.trajectory.empty() ? presetSequence(options, rig) : fileSequence(options, rig);
  const int frames = static_cast<int>(seq.t_ns.size());
  if (frames == 0) throw InputError("--seconds: the sequence has no frames at this rate");

  // Objects stay clear of every camera and of the body along the whole path.
  std::vector<Eigen::Vector3d> keep_out;
  for (const SE3d& T : seq.T_world_body) {
    keep_out.push_back(T.translation());
    for (const CameraCalibration& c : rig.cameras) keep_out.push_back((T * c.T_body_cam).translation());
  }
  SceneConfig scene_config;
  scene_config.room = seq.room;
  scene_config.keep_out_m = kObjectClearanceM;
  const Scene scene = Scene::generate(scene_config, keep_out, options.scene_seed);

  std::vector<RayTable> rays;
  for (const CameraCalibration& c : rig.cameras) rays.push_back(makeRayTable(c));

  if (options.progress) {
    fmt::print(
        stderr,
        "voca synth: {} frames at {} Hz, {} {}x{} stereo, room {:.1f} x {:.1f} x {:.1f} m, {} boxes, {} cylinders\n",
        frames, options.rate_hz, options.camera, rig.cameras[0].width, rig.cameras[0].height,
        seq.room.max.x() - seq.room.min.x(), seq.room.max.y() - seq.room.min.y(), seq.room.max.z() - seq.room.min.z(),
        scene.boxes().size(), scene.cylinders().size());
  }

  fs::create_directories(options.out);
  EurocWriter writer(options.out, 2);
  std::vector<GrayImage> images(2);
  auto last_report = std::chrono::steady_clock::now();
  platform::ProgressLine progress;
  const CameraCalibration& cam0 = rig.cameras[0];
  const Project project_cam0 = [&cam0](const Eigen::Vector3d& p, Eigen::Vector2d& uv) {
    return cam0.camera.project(p, uv) && uv.x() >= 0 && uv.y() >= 0 && uv.x() < cam0.width && uv.y() < cam0.height;
  };
  std::vector<SE3d> exposure_body;  // body poses while the shutter is open, for the current frame
  std::vector<SE3d> exposure_cam;
  std::vector<double> blur_px;
  int rendered = frames;  // fewer when stopped: what was rendered becomes the sequence
  for (int k = 0; k < frames; ++k) {
    if (options.stop_requested && options.stop_requested()) {
      rendered = k;
      break;
    }
    exposure_body.assign(1, seq.T_world_body[k]);
    if (options.exposure_ms > 0.0) {
      // Enough poses that consecutive ones move the image by at most about a pixel, measured on cam0
      // between the shutter's opening and closing.
      const auto half_ns = static_cast<int64_t>(std::llround(options.exposure_ms * 0.5e6));
      const SE3d ends[2] = {seq.body_pose_at(seq.t_ns[k] - half_ns) * cam0.T_body_cam,
                            seq.body_pose_at(seq.t_ns[k] + half_ns) * cam0.T_body_cam};
      const double streak_px = measureImageMotion(scene, rays[0], project_cam0, ends, 32).p90_px;
      blur_px.push_back(streak_px);
      const int samples = std::clamp(static_cast<int>(std::ceil(streak_px)) + 1, 2, 24);
      exposure_body.clear();
      for (int i = 0; i < samples; ++i) {
        const double f = (static_cast<double>(i) + 0.5) / static_cast<double>(samples) - 0.5;
        exposure_body.push_back(
            seq.body_pose_at(seq.t_ns[k] + static_cast<int64_t>(std::llround(f * 2.0 * static_cast<double>(half_ns)))));
      }
    }
    for (int c = 0; c < 2; ++c) {
      exposure_cam.clear();
      for (const SE3d& T : exposure_body) exposure_cam.push_back(T * rig.cameras[c].T_body_cam);
      RenderSettings settings;
      settings.noise_sigma = static_cast<float>(options.noise_sigma);
      settings.psf_sigma_px = static_cast<float>(options.psf_sigma_px);
      settings.noise_seed = options.seed;
      settings.frame_index = static_cast<std::uint64_t>(k);
      settings.camera_index = c;
      settings.supersample = options.supersample;
      settings.gain = static_cast<float>(options.gain);
      renderImage(scene, rays[c], exposure_cam, settings, images[c], options.threads);
    }
    const GrayView views[2] = {images[0].view(), images[1].view()};
    writer.addFrame(seq.t_ns[k], views);
    const auto now = std::chrono::steady_clock::now();
    if (options.progress && (k + 1 == frames || now - last_report > std::chrono::seconds(2))) {
      const double elapsed = std::chrono::duration<double>(now - start).count();
      progress.update("voca synth: frame {}/{}  {:.1f} s elapsed, {:.1f} s left", k + 1, frames, elapsed,
                      elapsed / (k + 1) * (frames - k - 1));
      last_report = now;
    }
  }
  progress.end();
  writer.finish();

  Trajectory ground_truth;
  for (int k = 0; k < rendered; ++k) ground_truth.poses.push_back({seq.t_ns[k], seq.T_world_body[k]});
  const fs::path gt_dir = options.out / "mav0" / "state_groundtruth_estimate0";
  fs::create_directories(gt_dir);
  saveTrajectory(ground_truth, gt_dir / "data.csv", TrajectoryFormat::kEuroc);
  saveBasaltCalibration(rig, options.out / "calib.json");

  // Report the true optical flow of cam0 on a coarse grid, so users see what the preset produces.
  std::vector<SE3d> T_world_cam0;
  for (int k = 0; k < rendered; ++k) T_world_cam0.push_back(seq.T_world_body[k] * rig.cameras[0].T_body_cam);
  SynthResult result;
  result.frames = rendered;
  result.planned_frames = frames;
  result.stopped = rendered < frames;
  if (!result.stopped && !options.trajectory.empty() && frames < trajectoryFrameLimit(options)) {
    result.warnings.push_back(
        fmt::format("--seconds {}: {} from --start {} s holds only {} frames at {} Hz; wrote those", *options.seconds,
                    options.trajectory.string(), options.start_s, frames, options.rate_hz));
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.motion = measureImageMotion(scene, rays[0], project_cam0, T_world_cam0, 32);
  if (!blur_px.empty()) {
    result.blur_median_px = quantileInPlace(blur_px, 0.5);
    result.blur_max_px = quantileInPlace(blur_px, 1.0);
  }
  return result;
}

}  // namespace voca::pipeline
