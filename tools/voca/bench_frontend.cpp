// `voca bench frontend` and the in-memory sequence loader shared with `voca track`.

#include "tools/voca/bench_frontend.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <memory>
#include <thread>

#include "drivers/dataset/dataset.h"
#include "drivers/decode/video_reader.h"
#include "drivers/encode/dataset_encoder.h"
#include "platform/filesystem/temp_dir.h"
#include "voca/config/config.h"
#include "voca/core/error.h"
#include "voca/frontend/frontend.h"
#include "voca/frontend/simd4.h"
#include "voca/image/png_io.h"

namespace voca::cli {

namespace {

void decodeVideoDataset(const Dataset& dataset, int max_frames, LoadedSequence& seq) {
  decode::DecoderOptions options;
  options.log_choice = false;
  decode::StereoVideoReader reader(dataset, options);
  decode::DecodedFrame left, right;
  while (reader.next(left, right)) {
    if (max_frames > 0 && static_cast<int>(seq.frames.size()) >= max_frames) break;
    LoadedStereoFrame& frame = seq.frames.emplace_back();
    frame.t_ns = left.t_ns;
    frame.left = left.luma;
    frame.right = right.luma;
    frame.motion_left = left.motion;
    frame.motion_right = right.motion;
    frame.type = left.type;
    if (seq.frames.size() % 50 == 0) fmt::print(stderr, "\rdecoded {} frames", seq.frames.size());
  }
  fmt::print(stderr, "\rdecoded {} frames\n", seq.frames.size());
  seq.has_motion = true;
}

}  // namespace

LoadedSequence loadStereoSequence(const std::filesystem::path& input, const LoadOptions& options) {
  const Dataset dataset = openDataset(input);
  for (const std::string& warning : dataset.warnings) fmt::print(stderr, "warning: {}\n", warning);
  LoadedSequence seq;
  const std::optional<std::filesystem::path> calibration =
      options.calibration ? options.calibration : dataset.calibration;
  if (!calibration) {
    throw InputError(fmt::format("{}: no calibration found beside the dataset; pass one with --calib", input.string()));
  }
  seq.rig = loadCalibration(*calibration);
  if (seq.rig.cameras.size() < 2) throw InputError(fmt::format("{}: need a stereo calibration", calibration->string()));

  if (dataset.layout == DatasetLayout::kVocaVideo) {
    seq.description = fmt::format("video {} ", input.string());
    decodeVideoDataset(dataset, options.max_frames, seq);
  } else if (options.encode_bitrate_bps > 0) {
    TempDir temp("voca-bench");
    encode::DatasetEncodeOptions encode_options;
    encode_options.settings.bitrate_bps = options.encode_bitrate_bps;
    encode_options.calibration = options.calibration;
    encode::silenceCodecLogs();
    encode::encodeDataset(input, temp.path(), encode_options, [](int camera, int pass, int passes, int frame, int n) {
      if (frame % 50 == 0 || frame + 1 == n) {
        fmt::print(stderr, "\rencoding camera {} pass {}/{}: frame {}/{}", camera, pass, passes, frame + 1, n);
      }
    });
    fmt::print(stderr, "\n");
    seq.description = fmt::format("{} encoded at {} kbit/s ", input.string(), options.encode_bitrate_bps / 1000);
    decodeVideoDataset(openDataset(temp.path()), options.max_frames, seq);
  } else {
    seq.description = fmt::format("raw images {} ", input.string());
    for (const StereoFrameRef& ref : dataset.frames) {
      if (options.max_frames > 0 && static_cast<int>(seq.frames.size()) >= options.max_frames) break;
      LoadedStereoFrame& frame = seq.frames.emplace_back();
      frame.t_ns = ref.t_ns;
      readPngGray(ref.left, frame.left);
      readPngGray(ref.right, frame.right);
    }
  }
  if (seq.frames.empty()) throw InputError(fmt::format("{}: no stereo frames", input.string()));
  for (int c = 0; c < 2; ++c) {
    const CameraCalibration& cam = seq.rig.cameras[static_cast<std::size_t>(c)];
    const GrayImage& image = c == 0 ? seq.frames[0].left : seq.frames[0].right;
    if (image.width() != cam.width || image.height() != cam.height) {
      throw InputError(fmt::format("{}: camera {} images are {}x{} but the calibration {} says {}x{}", input.string(),
                                   c, image.width(), image.height(), seq.rig.source, cam.width, cam.height));
    }
  }
  seq.description +=
      fmt::format("({} frames, {}x{})", seq.frames.size(), seq.frames[0].left.width(), seq.frames[0].left.height());
  return seq;
}

namespace {

struct FrontendBenchOptions {
  std::string input;
  std::string calib;
  std::string config;
  std::string bitrate = "500k";
  int frames = 0;
  int repeat = 3;
  int max_points = 1000;
  std::vector<std::string> modes = {"none", "mv", "of_then_mv", "mv_then_of", "mv_parallel_of"};
};

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t index =
      std::min(values.size() - 1, static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5));
  return values[index];
}

int runFrontendBench(const FrontendBenchOptions& opts) {
  if (opts.repeat < 1) throw InputError(fmt::format("--repeat: expected at least 1, got {}", opts.repeat));
  FrontendConfig base = opts.config.empty() ? FrontendConfig{} : loadConfig(opts.config).frontend;
  std::vector<PriorMode> modes;
  for (const std::string& name : opts.modes) {
    const auto mode = parsePriorMode(name);
    if (!mode) {
      throw InputError(
          fmt::format("--modes: unknown mode \"{}\" (none, mv, of_then_mv, mv_then_of, mv_parallel_of)", name));
    }
    modes.push_back(*mode);
  }
  LoadOptions load;
  if (!opts.calib.empty()) load.calibration = opts.calib;
  load.max_frames = opts.frames;
  load.encode_bitrate_bps = encode::parseBitrate(opts.bitrate);
  const LoadedSequence seq = loadStereoSequence(opts.input, load);

  std::string cpu = "unknown CPU";
  {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpuinfo, line)) {
      if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) {
        cpu = line.substr(line.find(':') + 2);
        break;
      }
    }
  }
  fmt::print(
      "machine: {} ({} hardware threads, KLT kernels: {}); frontend on one thread, thread CPU time per "
      "stereo frame\n",
      cpu, std::thread::hardware_concurrency(), voca::simd4::Native::kName);
  fmt::print("input: {}\n", seq.description);
  fmt::print("{:<16} {:>9} {:>9} {:>9} {:>9} {:>10} {:>10}\n", "mode", "median ms", "p99 ms", "mean ms", "wall p50",
             "left pts", "right pts");
  for (PriorMode mode : modes) {
    FrontendConfig config = base;
    config.prior_mode = mode;
    std::vector<double> cpu_ms, wall_ms;
    double left_points = 0.0, right_points = 0.0;
    int counted = 0;
    for (int r = 0; r < opts.repeat; ++r) {
      KltFrontend frontend(config, seq.rig, {.max_points = opts.max_points});
      TrackedStereoFrame out;
      FrontendStats stats;
      for (std::size_t k = 0; k < seq.frames.size(); ++k) {
        const LoadedStereoFrame& f = seq.frames[k];
        FrontendInput in;
        in.images = {f.left.view(), f.right.view()};
        if (seq.has_motion) in.motion = {&f.motion_left, &f.motion_right};
        in.picture_type = f.type;
        in.t_ns = f.t_ns;
        const double cpu_start = threadCpuMs();
        const auto wall_start = std::chrono::steady_clock::now();
        frontend.track(in, out, stats);
        const double cpu_elapsed = threadCpuMs() - cpu_start;
        const double wall_elapsed =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_start).count();
        if (k == 0) continue;  // the first frame only detects
        cpu_ms.push_back(cpu_elapsed);
        wall_ms.push_back(wall_elapsed);
        left_points += stats.num_left;
        right_points += stats.num_right;
        ++counted;
      }
      fmt::print(stderr, "\r{} repeat {}/{}   ", priorModeName(mode), r + 1, opts.repeat);
    }
    fmt::print(stderr, "\r");
    double mean = 0.0;
    for (double v : cpu_ms) mean += v;
    mean /= std::max<std::size_t>(1, cpu_ms.size());
    fmt::print("{:<16} {:9.3f} {:9.3f} {:9.3f} {:9.3f} {:10.0f} {:10.0f}\n", priorModeName(mode),
               percentile(cpu_ms, 0.5), percentile(cpu_ms, 0.99), mean, percentile(wall_ms, 0.5),
               left_points / std::max(1, counted), right_points / std::max(1, counted));
  }
  fmt::print("targets per stereo frame on one core: none <= 1.5 ms, mv_parallel_of <= 3 ms (median)\n");
  return 0;
}

}  // namespace

Runner configureFrontendBench(CLI::App& app) {
  auto opts = std::make_shared<FrontendBenchOptions>();
  app.add_option("input", opts->input, "Raw dataset (EuRoC/TUM-VI/KITTI folder) or VOCA video folder")->required();
  app.add_option("--calib", opts->calib, "Calibration file (default: the one found with the dataset)");
  app.add_option("--config", opts->config,
                 "Config JSON file, or a shipped config by name: euroc, tumvi, kitti (default: euroc)");
  app.add_option("--bitrate", opts->bitrate, "Raw datasets are encoded at this rate first to get motion vectors")
      ->capture_default_str();
  app.add_option("--frames", opts->frames, "Use only the first N frames (0 = all)")->capture_default_str();
  app.add_option("--repeat", opts->repeat, "Runs over the sequence per mode")->capture_default_str();
  app.add_option("--max-points", opts->max_points, "Frontend capacity: points per camera")->capture_default_str();
  app.add_option("--modes", opts->modes, "Prior modes to time")->capture_default_str();
  app.footer(
      "Loads the whole sequence into memory (decoding excluded from the timing), then runs the frontend\n"
      "over it for each prior mode and prints the thread CPU time per stereo frame (median, p99, mean),\n"
      "the wall-clock median and the mean number of left/right points. The first frame (detection only)\n"
      "is not counted.");
  return [opts] { return runFrontendBench(*opts); };
}

}  // namespace voca::cli
