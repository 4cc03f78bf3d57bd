// `voca bench pipeline`: the staged pipeline measured as a user runs it, decode included.

#include "tools/voca/bench_pipeline.h"

#include <fmt/core.h>
#include <malloc.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <thread>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "formats/dataset/dataset.h"
#include "pipeline/runtime/chrome_trace.h"
#include "pipeline/vo/vo_runner.h"
#include "platform/filesystem/temp_dir.h"
#include "platform/realtime/stop_signal.h"
#include "platform/realtime/thread_control.h"
#include "platform/terminal/progress_line.h"
#include "tools/voca/number_checks.h"
#include "tools/voca/pipeline_cli.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"
#include "voca_rt/run.h"

namespace voca::cli {

namespace {

struct PipelineBenchOptions {
  std::string input;
  std::string config;
  std::string bitrate = "500k";
  std::string mode;
  int repeat = 3;
  int frames = 0;
  bool skip_realtime = false;
  std::string decoder = "auto";
};

// Peak resident memory of this process since the last reset, in MiB (VmHWM).
double peakRssMiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0.0;
}

// Starts a new peak-memory measurement (Linux 4.0+: writing 5 to clear_refs resets VmHWM). The heap
// the previous run freed is handed back to the OS first, so each run's peak is its own, as in a
// process that runs the VO once.
void resetPeakRss() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
  std::ofstream("/proc/self/clear_refs") << "5";
}

int runPipelineBench(const PipelineBenchOptions& opts) {
  if (opts.repeat < 1) throw InputError(fmt::format("--repeat: expected at least 1, got {}", opts.repeat));
  platform::installStopHandlers();
  std::filesystem::path input = opts.input;
  std::optional<TempDir> encoded;
  if (openDataset(input).layout != DatasetLayout::kVocaVideo) {
    encoded.emplace("voca-bench");
    if (!encode::encodeForReplay(input, encoded->path(), encode::parseBitrate(opts.bitrate), std::nullopt, true,
                                 platform::stopRequested)) {
      return platform::interruptedExitCode(platform::stopSignal());
    }
    input = encoded->path();
  }
  // Through the library API, as a program would run it (the same staged pipeline as `voca run`).
  const auto makeOptions = [&](int threads, int camera_threads) {
    voca_rt::Options options;
    options.config = opts.config;
    options.mode = opts.mode;
    options.decoder = opts.decoder;
    options.threads = threads;
    options.frontend_threads = camera_threads;
    options.stop_requested = platform::stopRequested;
    return options;
  };
  voca_rt::Input source;
  source.path = input.string();
  source.max_frames = opts.frames;

  fmt::print("machine: {} cores available to this process\n", platform::availableCores());
  struct Layout {
    const char* label;
    int threads;
    int camera_threads;
    std::vector<double> fps;
    double rss = 0.0;
    voca_rt::Summary last;
  };
  std::vector<Layout> layouts = {{"1 thread", 1, 1, {}, 0.0, {}},
                                 {"staged (one thread per stage)", 0, 1, {}, 0.0, {}},
                                 {"staged, frontend on 2 threads", 0, 2, {}, 0.0, {}}};
  platform::ProgressLine progress;
  for (int r = 0; r < opts.repeat; ++r) {
    for (Layout& layout : layouts) {
      resetPeakRss();
      layout.last = voca_rt::run(source, makeOptions(layout.threads, layout.camera_threads));
      if (!layout.last.error.empty() || layout.last.stop_signal != 0) {
        progress.end();
        return reportRunEnd(layout.last, PipelineCli{}, "bench");
      }
      layout.rss = std::max(layout.rss, peakRssMiB());
      layout.fps.push_back(layout.last.frames_per_second);
      progress.update("{} run {}/{}: {:.1f} frames/s", layout.label, r + 1, opts.repeat, layout.fps.back());
    }
  }
  progress.end();
  fmt::print("input: {}\n", layouts[0].last.input);
  fmt::print("offline throughput, decode included (median of {} runs, wall clock):\n", opts.repeat);
  for (const Layout& layout : layouts) {
    fmt::print("  {:<32} {:7.1f} stereo frames/s  ({} threads; peak RSS {:.0f} MiB)\n", layout.label,
               voca::median(layout.fps), layout.last.threads, layout.rss);
  }
  const double single = std::max(voca::median(layouts[0].fps), 1e-9);
  fmt::print(
      "  pipelining speed-up: {:.2f}x, {:.2f}x with the frontend on 2 threads (target >= 1.8x on 2 cores; >= 200 "
      "frames/s with faster stages)\n",
      voca::median(layouts[1].fps) / single, voca::median(layouts[2].fps) / single);
  fmt::print("where the time goes, staged run with the frontend on 2 threads (service time per stage):\n");
  std::fputs(layouts[2].last.latency_report.c_str(), stdout);

  if (!opts.skip_realtime) {
    voca_rt::Input paced = source;
    paced.realtime = true;
    resetPeakRss();
    const voca_rt::Summary live = voca_rt::run(paced, makeOptions(0, 0));
    if (!live.error.empty() || live.stop_signal != 0) return reportRunEnd(live, PipelineCli{}, "bench");
    const std::array<double, 4>& e = live.end_to_end_ms;
    fmt::print("at the recording's real rate (--realtime), {} frames, peak RSS {:.0f} MiB (target <= 100):\n",
               live.frames, peakRssMiB());
    fmt::print("  arrival to pose written: p50 {:.2f} ms, p90 {:.2f} ms, p99 {:.2f} ms, max {:.2f} ms; {} dropped\n",
               e[0], e[1], e[2], e[3], live.dropped);
    std::fputs(live.latency_report.c_str(), stdout);
  }
  return 0;
}

}  // namespace

Runner configurePipelineBench(CLI::App& app) {
  auto opts = std::make_shared<PipelineBenchOptions>();
  app.add_option("input", opts->input, "Raw dataset (encoded first at --bitrate) or VOCA video folder")->required();
  app.add_option("--config", opts->config, "Config JSON file or shipped name (default: euroc)");
  app.add_option("--mode", opts->mode, "Prior mode: " + priorModeList() + " (default: the config's)");
  app.add_option("--bitrate", opts->bitrate, "Raw datasets are encoded at this rate first")->capture_default_str();
  app.add_option("--repeat", opts->repeat, "Offline runs per thread layout")->capture_default_str();
  app.add_option("--frames", opts->frames, "Use only the first N frames (0 = all)")
      ->capture_default_str()
      ->check(nonNegativeNumber());
  app.add_flag("--no-realtime", opts->skip_realtime, "Skip the real-rate latency run");
  app.add_option("--decoder", opts->decoder, "Decoder: auto, software, vaapi or v4l2m2m")->capture_default_str();
  app.footer(
      "Offline: the whole VO (read, decode, frontend, backend, write; trajectory kept in memory only) with\n"
      "every stage in one thread, with one thread per stage, and with one thread per stage and the frontend's\n"
      "helper thread (--frontend-threads 2), alternating, --repeat times each; prints\n"
      "the median stereo frames/s of each, the speed-up, peak RSS and the per-stage latency table. Then one\n"
      "run paced at the recording's timestamps (--realtime) for the latency a live user sees: arrival of a\n"
      "frame to its pose being written, p50/p90/p99/max, and frames dropped. Measure on an idle machine.");
  return [opts] { return runPipelineBench(*opts); };
}

}  // namespace voca::cli
