#include "pipeline/vo/run_summary.h"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>

#include "platform/realtime/clock.h"
#include "voca/frontend/detector.h"

namespace voca::pipeline {

namespace {

double pct(std::int64_t a, std::int64_t b) {
  return b > 0 ? 100.0 * static_cast<double>(a) / static_cast<double>(b) : 0.0;
}

}  // namespace

std::string noEstimateReason(const VoRunResult& result, int max_points) {
  const FrontendConfig& tracker = result.config.frontend;
  const int cells = detectionCells(result.width, result.height, tracker.grid_size_px, tracker.detection_border_px);
  std::string reason = fmt::format("no pose was estimated: all {} frames were lost", result.frames);
  if (max_points < result.config.backend.min_inliers) {
    return reason + fmt::format(
                        ". The tracker keeps at most {} point{} per camera (--max-points), fewer than the {} a "
                        "frame needs (backend min_inliers)",
                        max_points, max_points == 1 ? "" : "s", result.config.backend.min_inliers);
  }
  if (cells < result.config.backend.min_inliers) {
    return reason + fmt::format(
                        ". The {}x{} images hold {} grid cells for corners (frontend grid_size_px {}, "
                        "detection_border_px {}), fewer than the {} points a frame needs (backend min_inliers): "
                        "lower those keys in the config",
                        result.width, result.height, cells, tracker.grid_size_px, tracker.detection_border_px,
                        result.config.backend.min_inliers);
  }
  return reason +
         ". Check the calibration (image size, intrinsics, the cameras' relative pose) and the config; the "
         "messages above give each frame's reason";
}

std::string formatRunSummary(const VoRunResult& r) {
  std::string text;
  auto out = std::back_inserter(text);
  fmt::format_to(out, "input: {}\n", r.description);
  fmt::format_to(out, "mode: {}{}\n", priorModeName(r.config.frontend.prior_mode),
                 r.has_motion ? "" : " (raw images: no motion vectors)");
  fmt::format_to(out, "frames: {}, keyframes: {}, resets: {}, lost: {}\n", r.frames, r.backend.keyframes,
                 r.backend.resets, r.backend.lost);
  const StageReport* frontend = r.pipeline_report.stage("frontend");
  const StageReport* backend = r.pipeline_report.stage("backend");
  if (frontend != nullptr && backend != nullptr) {
    fmt::format_to(
        out,
        "ms per frame: frontend median {:.2f} (mean {:.2f}, p99 {:.2f}), backend median {:.2f} (mean {:.2f}, "
        "p99 {:.2f})\n",
        platform::nsToMs(frontend->service.quantileNs(0.5)), frontend->service.meanNs() * 1e-6,
        platform::nsToMs(frontend->service.quantileNs(0.99)), platform::nsToMs(backend->service.quantileNs(0.5)),
        backend->service.meanNs() * 1e-6, platform::nsToMs(backend->service.quantileNs(0.99)));
  }
  if (r.started) {
    fmt::format_to(out, "pipeline: {} thread{}{}, {:.1f} frames/s ({:.2f} s)\n", r.pipeline_report.threads,
                   r.pipeline_report.threads == 1 ? "" : "s",
                   r.frontend_camera_threads > 1 ? " (and a frontend helper sharing the tracking)" : "",
                   r.pipeline_report.wall_s > 0.0
                       ? static_cast<double>(r.pipeline_report.completed) / r.pipeline_report.wall_s
                       : 0.0,
                   r.pipeline_report.wall_s);
  }
  if (r.pipeline_report.dropped > 0 || r.pipeline_report.damaged > 0) {
    fmt::format_to(out, "skipped frames: {} dropped (live policy), {} damaged:", r.pipeline_report.dropped,
                   r.pipeline_report.damaged);
    int listed = 0;
    for (const ReleasedFrame& f : r.pipeline_report.released) {
      if (f.reason != ReleaseReason::kDropped && f.reason != ReleaseReason::kDamaged) continue;
      if (listed++ == 20) {
        fmt::format_to(out, " ...");
        break;
      }
      fmt::format_to(out, " {}{}", f.frame_index, f.reason == ReleaseReason::kDamaged ? "(damaged)" : "");
    }
    fmt::format_to(out, "\n");
  }
  if (r.source.frames_lost > 0 || r.source.unpaired > 0 || !r.source_end.empty()) {
    fmt::format_to(out, "source: {} frames lost before capture (driver or network), {} unpaired stereo frames{}\n",
                   r.source.frames_lost, r.source.unpaired,
                   r.source_end.empty() ? "" : fmt::format("; ended: {}", r.source_end));
  }
  if (r.eval) {
    fmt::format_to(out, "ground truth: {} ({} poses associated)\n", r.ground_truth, r.eval->ate.stats.count);
    fmt::format_to(out, "ATE: {:.4f} m RMSE{}\n", r.eval->ate.stats.rmse, r.eval->ate_divergent ? " (divergent)" : "");
    if (r.eval->rte) {
      fmt::format_to(out, "RTE (6 frames): {:.4f} m RMSE{}\n", r.eval->rte->stats.rmse,
                     r.eval->rte_divergent ? " (divergent)" : "");
    }
  } else if (!r.started) {
    fmt::format_to(out, "ATE/RTE: not computed (stopped before the first frame)\n");
  } else if (!r.ground_truth.empty()) {
    fmt::format_to(out, "ground truth: {}, not evaluated ({})\n", r.ground_truth,
                   r.failure.empty() ? "see the warning" : "no pose was estimated");
  } else {
    fmt::format_to(out, "no ground truth with the dataset: ATE/RTE not computed\n");
  }
  return text;
}

std::string formatTrackSummary(const VoRunResult& r, const FrontendConfig& config) {
  std::string text;
  auto out = std::back_inserter(text);
  const FrontendTotals& t = r.frontend;
  const double frames = static_cast<double>(std::max<std::int64_t>(r.frames, 1));
  fmt::format_to(out, "input: {}\n", r.description);
  fmt::format_to(out, "mode: {}{}, pattern {}, levels {}, grid {} px\n", priorModeName(config.prior_mode),
                 r.has_motion ? "" : " (raw images: no motion vectors, priors inactive)", config.pattern,
                 config.pyramid_levels, config.grid_size_px);
  fmt::format_to(out, "tracks per frame: left mean {:.1f} (min {}, max {}), right mean {:.1f}\n",
                 static_cast<double>(t.left_points) / frames, t.min_left, t.max_left,
                 static_cast<double>(t.right_points) / frames);
  fmt::format_to(out, "survival frame to frame: {:.1f} % of {} temporal tracks kept (both cameras)\n",
                 pct(t.kept, t.previous), t.previous);
  fmt::format_to(out, "with motion vector: {:.1f} %{}; tracked from previous position: {}, from MV prior: {}\n",
                 pct(t.with_vector, t.previous),
                 t.distrusted > 0 ? fmt::format(" ({:.1f} % of them distrusted)", pct(t.distrusted, t.with_vector))
                                  : std::string(),
                 t.tracked_plain, t.tracked_prior);
  if (t.prior_confirmed > 0) {
    fmt::format_to(out,
                   "prior tracks not run, the vector landing within prior_agree_radius_px of the plain result: {}\n",
                   t.prior_confirmed);
  }
  fmt::format_to(out,
                 "rescued by the prior: {} ({:.2f} per frame); consensus rejections: {} ({:.2f} per frame); bridged "
                 "I-frames: {}\n",
                 t.rescued, static_cast<double>(t.rescued) / frames, t.consensus,
                 static_cast<double>(t.consensus) / frames, t.bridged_frames);
  // r.has_motion: the frames were decoded from video (raw ones have no vectors).
  if (appliesTo(config.retry_previous_flow, r.has_motion)) {
    fmt::format_to(out, "kept by the retry from the previous image flow (retry_previous_flow): {} ({:.2f} per frame)\n",
                   t.flow_retried, static_cast<double>(t.flow_retried) / frames);
    if (t.flow_searched > 0) {
      fmt::format_to(out,
                     "  retries with no flow measured yet (the run started in fast motion) started from the whole "
                     "image's shift: {} camera steps\n",
                     t.flow_searched);
    }
  }
  fmt::format_to(out, "new points: {:.1f} per frame, {:.1f} % matched in the right image; epipolar rejections: {}\n",
                 static_cast<double>(t.detected) / frames, pct(t.stereo_matched, t.detected), t.epipolar);
  if (config.detection_nonoverlap) {
    fmt::format_to(out, "right-only points (detection_nonoverlap): {:.1f} new per frame\n",
                   static_cast<double>(t.detected_right_only) / frames);
  }
  if (config.stereo_rematch) {
    fmt::format_to(out, "left tracks found again in the right image (stereo_rematch): {:.1f} per frame\n",
                   static_cast<double>(t.stereo_rematched) / frames);
  }
  if (config.thin_when_full_px > 0.0) {
    fmt::format_to(out, "tracks dropped next to an older one (thin_when_full_px {}): {:.1f} per frame\n",
                   config.thin_when_full_px, static_cast<double>(t.thinned) / frames);
  }
  if (t.guess_prior.count() > 0) {
    fmt::format_to(out,
                   "guess to converged distance (px, {} kept tracks with a vector): previous position median {} p90 "
                   "{}; MV prior median {} p90 {}\n",
                   t.guess_prior.count(), t.guess_plain.formatQuantile(0.5), t.guess_plain.formatQuantile(0.9),
                   t.guess_prior.formatQuantile(0.5), t.guess_prior.formatQuantile(0.9));
  }
  if (const StageReport* frontend = r.pipeline_report.stage("frontend")) {
    fmt::format_to(
        out,
        "time per stereo frame: wall median {:.2f} ms, p99 {:.2f} ms; thread CPU median {:.2f} ms, p99 {:.2f} "
        "ms\n",
        platform::nsToMs(frontend->service.quantileNs(0.5)), platform::nsToMs(frontend->service.quantileNs(0.99)),
        platform::nsToMs(frontend->cpu.quantileNs(0.5)), platform::nsToMs(frontend->cpu.quantileNs(0.99)));
  }
  return text;
}

void printRunSummary(const VoRunResult& result, std::FILE* out) { std::fputs(formatRunSummary(result).c_str(), out); }

void printTrackSummary(const VoRunResult& result, const FrontendConfig& config, std::FILE* out) {
  std::fputs(formatTrackSummary(result, config).c_str(), out);
}

}  // namespace voca::pipeline
