// `voca track`: runs the KLT frontend alone on a raw dataset or a VOCA video folder and prints what
// it did (tracks, survival, prior rescues, consensus rejections, guess distances, time); optionally
// writes an overlay video of the tracks (previous position, MV prior, converged position).

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "drivers/decode/rgb_video_writer.h"
#include "drivers/encode/video_encoder.h"
#include "tools/voca/bench_frontend.h"
#include "tools/voca/command.h"
#include "voca/config/config.h"
#include "voca/core/error.h"
#include "voca/frontend/frontend.h"

namespace {

using voca::cli::Runner;

struct TrackOptions {
  std::string input;
  std::string calib;
  std::string config;
  std::string mode;
  std::string overlay;
  std::string encode;
  int frames = 0;
  int max_points = 1000;
  bool per_frame = false;
};

// ---- overlay drawing ------------------------------------------------------------------------

void putPixel(voca::RgbImage& image, int x, int y, voca::Rgb8 colour) {
  if (x >= 0 && y >= 0 && x < image.width() && y < image.height()) image(x, y) = colour;
}

void drawLine(voca::RgbImage& image, Eigen::Vector2f a, Eigen::Vector2f b, voca::Rgb8 colour) {
  const float length = (b - a).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(length)));
  if (steps > 4 * (image.width() + image.height())) return;  // a lost point far outside: not worth drawing
  for (int i = 0; i <= steps; ++i) {
    const Eigen::Vector2f p = a + (b - a) * (static_cast<float>(i) / static_cast<float>(steps));
    putPixel(image, static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())), colour);
  }
}

void drawCross(voca::RgbImage& image, Eigen::Vector2f p, int r, voca::Rgb8 colour) {
  const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
  for (int d = -r; d <= r; ++d) {
    putPixel(image, x + d, y + d, colour);
    putPixel(image, x + d, y - d, colour);
  }
}

void drawCircle(voca::RgbImage& image, Eigen::Vector2f p, float r, voca::Rgb8 colour) {
  const int n = static_cast<int>(std::ceil(2.f * 3.14159f * r));
  for (int i = 0; i < n; ++i) {
    const float a = 2.f * 3.14159265f * static_cast<float>(i) / static_cast<float>(n);
    putPixel(image, static_cast<int>(std::lround(p.x() + r * std::cos(a))),
             static_cast<int>(std::lround(p.y() + r * std::sin(a))), colour);
  }
}

// The left image with the temporal step of every point: blue dot = previous position, yellow
// cross and line = the motion-vector prior, green circle and line = converged position (red when
// the track was rejected).
void renderOverlay(const voca::GrayImage& gray, const voca::KltFrontend& frontend,
                   const voca::TrackedStereoFrame& frame, voca::RgbImage& out) {
  out.resize(gray.width(), gray.height());
  for (int y = 0; y < gray.height(); ++y) {
    for (int x = 0; x < gray.width(); ++x) {
      const std::uint8_t v = gray(x, y);
      out(x, y) = {v, v, v};
    }
  }
  const voca::Rgb8 blue{60, 140, 255}, yellow{255, 220, 0}, green{0, 230, 60}, red{255, 40, 40}, cyan{0, 220, 220};
  for (const voca::PointTrace& t : frontend.traces(0)) {
    if (t.has_prior) {
      drawLine(out, t.previous_px, t.prior_px, yellow);
      drawCross(out, t.prior_px, 2, yellow);
    }
    drawLine(out, t.previous_px, t.tracked_px, t.kept ? green : red);
    drawCircle(out, t.tracked_px, 3.f, t.kept ? green : red);
    putPixel(out, static_cast<int>(std::lround(t.previous_px.x())), static_cast<int>(std::lround(t.previous_px.y())),
             blue);
    drawCircle(out, t.previous_px, 1.f, blue);
  }
  // Points new in this frame (no trace yet).
  const auto traces = frontend.traces(0);
  for (const voca::KeypointObservation& o : frame.observations[0]) {
    const bool traced =
        std::any_of(traces.begin(), traces.end(), [&](const voca::PointTrace& t) { return t.track_id == o.track_id; });
    if (!traced) drawCircle(out, o.px, 4.f, cyan);
  }
}

// ---- summary --------------------------------------------------------------------------------

// CPU time of this thread: unlike wall time not inflated when other processes share the cores.
double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1,
                         static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5))];
}

struct Totals {
  std::vector<double> left_points, right_points, ms, cpu_ms;
  std::vector<double> plain_dist, prior_dist;
  long previous = 0, kept = 0, rescued = 0, consensus = 0, tracked_plain = 0, tracked_prior = 0, with_vector = 0;
  long detected = 0, detected_right_only = 0, stereo_matched = 0, epipolar = 0;
  int bridged_frames = 0;
  int frames = 0;
};

int runTrack(const TrackOptions& opts) {
  voca::FrontendConfig config = opts.config.empty() ? voca::FrontendConfig{} : voca::loadConfig(opts.config).frontend;
  if (!opts.mode.empty()) {
    const auto mode = voca::parsePriorMode(opts.mode);
    if (!mode) {
      throw voca::InputError(fmt::format(
          "--mode: unknown mode \"{}\" (expected none, mv, of_then_mv, mv_then_of or mv_parallel_of)", opts.mode));
    }
    config.prior_mode = *mode;
  }
  if (opts.frames < 0) throw voca::InputError("--frames: expected 0 (all) or a positive count");
  voca::cli::LoadOptions load;
  if (!opts.calib.empty()) load.calibration = opts.calib;
  load.max_frames = opts.frames;
  if (!opts.encode.empty()) load.encode_bitrate_bps = voca::encode::parseBitrate(opts.encode);
  const voca::cli::LoadedSequence seq = voca::cli::loadStereoSequence(opts.input, load);

  voca::KltFrontend frontend(config, seq.rig, {.max_points = opts.max_points});
  std::unique_ptr<voca::decode::RgbVideoWriter> writer;
  if (!opts.overlay.empty()) {
    voca::encode::silenceCodecLogs();  // libavcodec prints x264's settings at info level otherwise
    writer = std::make_unique<voca::decode::RgbVideoWriter>(opts.overlay, 20, 1);
  }
  voca::RgbImage overlay;
  voca::TrackedStereoFrame out;
  voca::FrontendStats stats;
  Totals totals;
  if (opts.per_frame) {
    fmt::print("{:>5} {:>4} {:>5} {:>5} {:>5} {:>5} {:>6} {:>7} {:>6} {:>7}\n", "frame", "type", "left", "right",
               "kept", "lost", "new", "rescued", "reject", "ms");
  }
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const voca::cli::LoadedStereoFrame& f = seq.frames[k];
    voca::FrontendInput in;
    in.images = {f.left.view(), f.right.view()};
    if (seq.has_motion) in.motion = {&f.motion_left, &f.motion_right};
    in.picture_type = f.type;
    in.t_ns = f.t_ns;
    const double cpu_start = threadCpuMs();
    frontend.track(in, out, stats);
    totals.cpu_ms.push_back(threadCpuMs() - cpu_start);

    ++totals.frames;
    totals.left_points.push_back(stats.num_left);
    totals.right_points.push_back(stats.num_right);
    totals.ms.push_back(stats.time_ms);
    for (const voca::TemporalStats& t : stats.temporal) {
      totals.previous += t.previous;
      totals.kept += t.kept;
      totals.rescued += t.rescued;
      totals.consensus += t.consensus_rejections;
      totals.tracked_plain += t.tracked_plain;
      totals.tracked_prior += t.tracked_prior;
      totals.with_vector += t.with_vector;
    }
    totals.detected += stats.detected;
    totals.detected_right_only += stats.detected_right_only;
    totals.stereo_matched += stats.stereo_matched;
    totals.epipolar += stats.epipolar_rejected;
    totals.bridged_frames += stats.bridged[0] || stats.bridged[1];
    totals.plain_dist.insert(totals.plain_dist.end(), stats.guess_dist_plain_px.begin(),
                             stats.guess_dist_plain_px.end());
    totals.prior_dist.insert(totals.prior_dist.end(), stats.guess_dist_prior_px.begin(),
                             stats.guess_dist_prior_px.end());
    if (opts.per_frame) {
      const voca::TemporalStats& t = stats.temporal[0];
      fmt::print("{:5} {:>4} {:5} {:5} {:5} {:5} {:6} {:7} {:6} {:7.2f}\n", k, voca::pictureTypeName(f.type),
                 stats.num_left, stats.num_right, t.kept, t.lost, stats.detected, t.rescued, t.consensus_rejections,
                 stats.time_ms);
    }
    if (writer) {
      renderOverlay(f.left, frontend, out, overlay);
      writer->write(overlay.view());
    }
    if ((k + 1) % 100 == 0) fmt::print(stderr, "\rtracked {}/{} frames", k + 1, seq.frames.size());
  }
  if (seq.frames.size() >= 100) fmt::print(stderr, "\n");
  if (writer) writer->finish();

  const auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / static_cast<double>(v.size());
  };
  const auto pct = [](long a, long b) { return b > 0 ? 100.0 * static_cast<double>(a) / static_cast<double>(b) : 0.0; };
  fmt::print("input: {}\n", seq.description);
  fmt::print("mode: {}{}, pattern {}, levels {}, grid {} px\n", voca::priorModeName(config.prior_mode),
             seq.has_motion ? "" : " (raw images: no motion vectors, priors inactive)", config.pattern,
             config.pyramid_levels, config.grid_size_px);
  fmt::print("tracks per frame: left mean {:.1f} (min {:.0f}, max {:.0f}), right mean {:.1f}\n",
             mean(totals.left_points), quantile(totals.left_points, 0.0), quantile(totals.left_points, 1.0),
             mean(totals.right_points));
  fmt::print("survival frame to frame: {:.1f} % of {} temporal tracks kept (both cameras)\n",
             pct(totals.kept, totals.previous), totals.previous);
  fmt::print("with motion vector: {:.1f} %; tracked from previous position: {}, from MV prior: {}\n",
             pct(totals.with_vector, totals.previous), totals.tracked_plain, totals.tracked_prior);
  fmt::print(
      "rescued by the prior: {} ({:.2f} per frame); consensus rejections: {} ({:.2f} per frame); bridged I-frames: "
      "{}\n",
      totals.rescued, static_cast<double>(totals.rescued) / totals.frames, totals.consensus,
      static_cast<double>(totals.consensus) / totals.frames, totals.bridged_frames);
  fmt::print("new points: {:.1f} per frame, {:.1f} % matched in the right image; epipolar rejections: {}\n",
             static_cast<double>(totals.detected) / totals.frames, pct(totals.stereo_matched, totals.detected),
             totals.epipolar);
  if (config.detection_nonoverlap) {
    fmt::print("right-only points (detection_nonoverlap): {:.1f} new per frame\n",
               static_cast<double>(totals.detected_right_only) / totals.frames);
  }
  if (!totals.prior_dist.empty()) {
    fmt::print(
        "guess to converged distance (px, {} kept tracks with a vector): previous position median {:.3f} p90 {:.3f}; "
        "MV prior median {:.3f} p90 {:.3f}\n",
        totals.prior_dist.size(), quantile(totals.plain_dist, 0.5), quantile(totals.plain_dist, 0.9),
        quantile(totals.prior_dist, 0.5), quantile(totals.prior_dist, 0.9));
  }
  fmt::print(
      "time per stereo frame: wall median {:.2f} ms, p99 {:.2f} ms; thread CPU median {:.2f} ms, p99 {:.2f} ms\n",
      quantile(totals.ms, 0.5), quantile(totals.ms, 0.99), quantile(totals.cpu_ms, 0.5), quantile(totals.cpu_ms, 0.99));
  if (writer) fmt::print("overlay: {}\n", opts.overlay);
  return 0;
}

const bool registered = voca::cli::registerCommand({
    .name = "track",
    .summary = "Run the KLT frontend alone on a dataset or video and summarise its tracks",
    .order = 40,
    .configure = [](CLI::App& app) -> Runner {
      auto opts = std::make_shared<TrackOptions>();
      app.add_option("input", opts->input, "Raw dataset (EuRoC/TUM-VI/KITTI folder) or VOCA video folder")->required();
      app.add_option("--calib", opts->calib, "Calibration file (default: the one found with the dataset)");
      app.add_option("--config", opts->config,
                     "Config JSON file, or a shipped config by name: euroc, tumvi, kitti (default: euroc)");
      app.add_option("--mode", opts->mode,
                     "Prior mode: none, mv, of_then_mv, mv_then_of, mv_parallel_of (overrides the config)");
      app.add_option("--overlay", opts->overlay, "Write the left video with the tracks drawn to this .mp4");
      app.add_option("--frames", opts->frames, "Track only the first N frames (0 = all)")->capture_default_str();
      app.add_option("--encode", opts->encode,
                     "Raw datasets: encode at this bitrate (e.g. 500k) and decode first, to track with motion vectors");
      app.add_option("--max-points", opts->max_points, "Points per camera (capacity)")->capture_default_str();
      app.add_flag("--per-frame", opts->per_frame, "Print one line per frame");
      app.footer(
          "Overlay colours: blue = previous position, yellow = motion-vector prior, green = converged\n"
          "position (red = rejected), cyan = new detection. Raw images carry no motion vectors, so the\n"
          "MV modes behave like `none` unless --encode is given.");
      return [opts] { return runTrack(*opts); };
    },
});

}  // namespace
