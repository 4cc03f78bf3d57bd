#include "tools/voca/run_vo.h"

#include <fmt/core.h>

#include <algorithm>

#include "drivers/dataset/dataset.h"
#include "drivers/decode/video_reader.h"
#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "platform/filesystem/temp_dir.h"
#include "voca/backend/estimator.h"
#include "voca/calib/calibration.h"
#include "voca/config/config.h"
#include "voca/core/error.h"
#include "voca/frontend/frontend.h"
#include "voca/image/png_io.h"

namespace voca::cli {

namespace {

// Stereo frames one at a time from either layout, so long sequences need no memory for all images.
class FrameSource {
 public:
  explicit FrameSource(const Dataset& dataset) : dataset_(dataset) {
    if (dataset.layout == DatasetLayout::kVocaVideo) {
      decode::DecoderOptions options;
      options.log_choice = false;
      video_ = std::make_unique<decode::StereoVideoReader>(dataset, options);
    }
  }
  bool hasMotion() const { return video_ != nullptr; }
  std::size_t size() const { return video_ ? video_->size() : dataset_.frames.size(); }

  bool next(FrontendInput& input) {
    if (video_) {
      if (!video_->next(left_, right_)) return false;
      input.images = {left_.luma.view(), right_.luma.view()};
      input.motion = {&left_.motion, &right_.motion};
      input.picture_type = left_.type;
      input.t_ns = left_.t_ns;
      return true;
    }
    if (index_ >= dataset_.frames.size()) return false;
    const StereoFrameRef& ref = dataset_.frames[index_++];
    readPngGray(ref.left, left_.luma);
    readPngGray(ref.right, right_.luma);
    input.images = {left_.luma.view(), right_.luma.view()};
    input.motion = {nullptr, nullptr};
    input.picture_type = PictureType::kUnknown;
    input.t_ns = ref.t_ns;
    return true;
  }

 private:
  const Dataset& dataset_;
  std::unique_ptr<decode::StereoVideoReader> video_;
  decode::DecodedFrame left_, right_;
  std::size_t index_ = 0;
};

std::optional<Trajectory> loadGroundTruth(const Dataset& dataset) {
  if (!dataset.ground_truth) return std::nullopt;
  if (dataset.layout == DatasetLayout::kKitti) {
    return loadTrajectory(*dataset.ground_truth, TrajectoryFormat::kKitti, dataset.root / "times.txt");
  }
  return loadTrajectory(*dataset.ground_truth);
}

}  // namespace

double quantileOf(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1,
                         static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5))];
}

double medianOf(std::vector<double> values) { return quantileOf(std::move(values), 0.5); }

VoRunResult runVisualOdometry(const VoRunOptions& options) {
  const Dataset raw = openDataset(options.input);
  for (const std::string& warning : raw.warnings) fmt::print(stderr, "warning: {}\n", warning);
  // KITTI's street scenes and 0.54 m baseline put the paper's 2 m stereo guess ~190 px off, so a
  // KITTI folder without an explicit config gets the shipped KITTI setting.
  const bool kitti_default = !options.config && raw.layout == DatasetLayout::kKitti;
  VocaConfig config = options.config  ? loadConfig(*options.config)
                      : kitti_default ? builtinConfig("kitti")
                                      : VocaConfig{};
  if (kitti_default && options.progress) fmt::print(stderr, "config: built-in 'kitti' (KITTI folder, no --config)\n");
  if (options.mode) config.frontend.prior_mode = *options.mode;
  const std::optional<std::filesystem::path> calibration = options.calibration ? options.calibration : raw.calibration;
  if (!calibration) {
    throw InputError(
        fmt::format("{}: no calibration found beside the dataset; pass one with --calib", options.input.string()));
  }
  StereoRig rig = loadCalibration(*calibration);
  if (rig.cameras.size() < 2) throw InputError(fmt::format("{}: need a stereo calibration", calibration->string()));

  VoRunResult result;
  result.mode = config.frontend.prior_mode;
  std::optional<TempDir> temp;
  Dataset dataset = raw;
  if (options.encode_bitrate_bps > 0 && raw.layout != DatasetLayout::kVocaVideo) {
    temp.emplace("voca-run");
    encode::DatasetEncodeOptions encode_options;
    encode_options.settings.bitrate_bps = options.encode_bitrate_bps;
    encode_options.calibration = options.calibration;
    encode::silenceCodecLogs();
    encode::encodeDataset(
        options.input, temp->path(), encode_options, [&](int camera, int pass, int passes, int frame, int n) {
          if (options.progress && (frame % 50 == 0 || frame + 1 == n)) {
            fmt::print(stderr, "\rencoding camera {} pass {}/{}: frame {}/{}", camera, pass, passes, frame + 1, n);
          }
        });
    if (options.progress) fmt::print(stderr, "\n");
    dataset = openDataset(temp->path());
    result.description =
        fmt::format("{} encoded at {} kbit/s", options.input.string(), options.encode_bitrate_bps / 1000);
  } else {
    result.description =
        fmt::format("{} {}", raw.layout == DatasetLayout::kVocaVideo ? "video" : "raw images", options.input.string());
  }

  FrameSource source(dataset);
  result.has_motion = source.hasMotion();
  KltFrontend frontend(config.frontend, rig, {.max_points = options.max_points});
  VoEstimator backend(config.backend, rig);
  TrackedStereoFrame tracked;
  tracked.reserve(static_cast<std::size_t>(options.max_points));
  FrontendStats stats;
  FrontendInput input;
  const std::size_t total =
      options.max_frames > 0 ? std::min<std::size_t>(source.size(), options.max_frames) : source.size();
  result.trajectory.poses.reserve(total);
  std::int64_t index = 0;
  while (result.frames < static_cast<int>(total) && source.next(input)) {
    if (input.images[0].width != rig.cameras[0].width || input.images[0].height != rig.cameras[0].height) {
      throw InputError(fmt::format("{}: images are {}x{} but the calibration {} says {}x{}", options.input.string(),
                                   input.images[0].width, input.images[0].height, rig.source, rig.cameras[0].width,
                                   rig.cameras[0].height));
    }
    frontend.track(input, tracked, stats);
    tracked.t_ns = input.t_ns;
    tracked.frame_index = index++;
    const PoseEstimate& estimate = backend.process(tracked);
    if (config.frontend.matching_guess == StereoGuess::kAverageDepth && estimate.mean_depth_m > 0.0) {
      frontend.setAverageDepth(estimate.mean_depth_m);
    }
    result.trajectory.poses.push_back({estimate.t_ns, estimate.T_world_body});
    ++result.frames;
    result.keyframes += estimate.keyframe;
    result.resets += estimate.state == TrackingState::kReset;
    result.lost += estimate.state == TrackingState::kLost;
    result.frontend_ms.push_back(stats.time_ms);
    result.backend_ms.push_back(estimate.time_ms);
    if (estimate.state != TrackingState::kTracking && options.progress) {
      fmt::print(stderr, "\nframe {}: {} ({})\n", result.frames - 1, trackingStateName(estimate.state),
                 failureReasonName(estimate.failure));
    }
    if (options.progress && (result.frames % 20 == 0 || result.frames == static_cast<int>(total))) {
      fmt::print(stderr, "\rframe {}/{}: {} landmarks, {} keyframes in the window, {:.1f} + {:.1f} ms", result.frames,
                 total, estimate.num_landmarks, estimate.num_keyframes, stats.time_ms, estimate.time_ms);
    }
  }
  if (options.progress) fmt::print(stderr, "\n");

  std::optional<Trajectory> gt;
  if (options.ground_truth) {
    gt = loadTrajectory(*options.ground_truth);
    result.ground_truth = options.ground_truth->string();
  } else if ((gt = loadGroundTruth(dataset))) {
    result.ground_truth = dataset.ground_truth->string();
  }
  if (gt) {
    EvalOptions eval_options;
    eval_options.expected_frames = static_cast<std::size_t>(result.frames);
    try {
      result.eval = evaluateTrajectory(result.trajectory, *gt, eval_options);
    } catch (const InputError& e) {
      fmt::print(stderr, "warning: cannot evaluate against {}: {}\n", result.ground_truth, e.what());
      result.ground_truth.clear();
    }
  }
  return result;
}

void printRunSummary(const VoRunResult& r) {
  const auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  };
  fmt::print("input: {}\n", r.description);
  fmt::print("mode: {}{}\n", priorModeName(r.mode), r.has_motion ? "" : " (raw images: no motion vectors)");
  fmt::print("frames: {}, keyframes: {}, resets: {}, lost: {}\n", r.frames, r.keyframes, r.resets, r.lost);
  fmt::print(
      "ms per frame: frontend median {:.2f} (mean {:.2f}, p99 {:.2f}), backend median {:.2f} (mean {:.2f}, p99 "
      "{:.2f})\n",
      medianOf(r.frontend_ms), mean(r.frontend_ms), quantileOf(r.frontend_ms, 0.99), medianOf(r.backend_ms),
      mean(r.backend_ms), quantileOf(r.backend_ms, 0.99));
  if (r.eval) {
    fmt::print("ground truth: {} ({} poses associated)\n", r.ground_truth, r.eval->ate.stats.count);
    fmt::print("ATE: {:.4f} m RMSE{}\n", r.eval->ate.stats.rmse, r.eval->ate_divergent ? " (divergent)" : "");
    if (r.eval->rte) {
      fmt::print("RTE (6 frames): {:.4f} m RMSE{}\n", r.eval->rte->stats.rmse,
                 r.eval->rte_divergent ? " (divergent)" : "");
    }
  } else {
    fmt::print("no ground truth with the dataset: ATE/RTE not computed\n");
  }
}

}  // namespace voca::cli
