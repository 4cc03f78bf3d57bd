// `voca bench <mode>`: throughput measurements on this machine, and evaluation suites. Each mode is one entry of kModes
// below (a name, a summary and a configure function declaring its options), so a new mode is one
// function plus one row.

#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <fmt/core.h>

#include "pipeline/bench/decode_bench.h"
#include "platform/machine/cpu_info.h"
#include "tools/voca/bench_backend.h"
#include "tools/voca/bench_frontend.h"
#include "tools/voca/bench_pipeline.h"
#include "tools/voca/bench_suite.h"
#include "tools/voca/command.h"

namespace {

using voca::cli::Runner;

// One `voca bench` sub-mode.
struct BenchMode {
  const char* name;
  const char* summary;
  std::function<Runner(CLI::App&)> configure;
};

void printMachine() {
  fmt::print("machine: {} ({} hardware threads); measured on one thread\n", voca::platform::cpuModel(),
             std::thread::hardware_concurrency());
}

// ---- decode ---------------------------------------------------------------------------------

int printDecodeBench(const voca::pipeline::DecodeBenchOptions& opts) {
  const voca::pipeline::DecodeBenchResult r = voca::pipeline::runDecodeBench(opts);
  printMachine();
  fmt::print(
      "video: {} ({}, {}x{}, {} packets, {:.0f} kbit/s at {:.4g} fps); demux {:.0f} packets/s (not timed below)\n",
      opts.video, r.stream.codec_name, r.stream.width, r.stream.height, r.packets, r.kbit_per_s, r.stream_fps,
      r.demux_packets_per_s);
  fmt::print("{}\n", r.decoder_description);
  fmt::print(
      "{} frames per run, {} runs per variant, medians (fps from this thread's CPU time; wall-clock fps\n"
      "also shown, lower when other processes share the cores):\n",
      r.frames, opts.repeat);
  for (const voca::pipeline::DecodeVariantResult& v : r.variants) {
    fmt::print("  {:<38} {:7.0f} fps  {:6.3f} ms/frame  (min {:.0f}, max {:.0f}; wall {:.0f} fps)\n", v.label,
               v.median_cpu_fps, 1000.0 / v.median_cpu_fps, v.min_cpu_fps, v.max_cpu_fps, v.median_wall_fps);
  }
  const double full_ms = 1000.0 / r.variants[0].median_cpu_fps, no_mv_ms = 1000.0 / r.variants[1].median_cpu_fps;
  fmt::print("  MV extraction overhead: {:+.3f} ms/frame ({:+.1f} %), {:.0f} vectors per frame\n", full_ms - no_mv_ms,
             100.0 * (full_ms - no_mv_ms) / no_mv_ms, r.vectors_per_frame);
  fmt::print("  MV-only parse vectors identical to full decode: {}\n", r.parse_vectors_identical ? "yes" : "NO");
  fmt::print("  targets (752x480, 500 kbit/s, one core): full + MV >= 1200 fps: {}; MV-only >= 1800 fps: {}\n",
             r.variants[0].median_cpu_fps >= 1200 ? "met" : "not met",
             r.variants[2].median_cpu_fps >= 1800 ? "met" : "not met");
  if (r.stream.width != 752 || r.stream.height != 480) {
    fmt::print("  (this video is {}x{}, so the targets are only indicative)\n", r.stream.width, r.stream.height);
  }
  return 0;
}

Runner configureDecodeBench(CLI::App& app) {
  auto opts = std::make_shared<voca::pipeline::DecodeBenchOptions>();
  app.add_option("video", opts->video, "Video file (.mp4 with H.264, MPEG-4 Part 2 or MPEG-2)")->required();
  app.add_option("--repeat", opts->repeat, "Timed runs per variant; medians are reported")->capture_default_str();
  app.add_option("--decoder", opts->decoder,
                 "Decoder for the full-decode variants: auto, software, vaapi or v4l2m2m (hardware decodes the\n"
                 "pixels, a software parse gives the vectors)")
      ->capture_default_str();
  app.footer(
      "Decodes the whole video in memory (demuxing excluded) on one thread with the chosen decoder, as\n"
      "(1) full decode with motion-vector export, (2) full decode without, (3) MV-only parse with the\n"
      "loop filter skipped, and prints frames per second and the cost of MV extraction.");
  return [opts] { return printDecodeBench(*opts); };
}

const std::vector<BenchMode>& benchModes() {
  static const std::vector<BenchMode> modes = {
      {"decode", "Decoder throughput: full decode with/without MV export, MV-only parse", configureDecodeBench},
      {"frontend", "Frontend CPU time per stereo frame for each prior mode", voca::cli::configureFrontendBench},
      {"pipeline", "Whole-pipeline frames/s offline (1 thread vs staged), latency at real rate, peak memory",
       voca::cli::configurePipelineBench},
      {"backend", "Estimator cost per frame on synthetic observations (7 keyframes, ~200 points)",
       voca::cli::configureBackendBench},
      {"suite", "Evaluation suite: sequences x bitrates x modes -> the paper's tables (resumable, --jobs, cluster)",
       voca::cli::configureSuiteBench},
      {"collect", "Tables from a suite folder whose runs ran elsewhere (--emit-jobs on a cluster)",
       voca::cli::configureCollectBench},
  };
  return modes;
}

const bool registered = voca::cli::registerCommand({
    .name = "bench",
    .summary = "Measure throughput of pipeline stages, or run evaluation suites for the paper's tables",
    .order = 70,
    .configure = [](CLI::App& app) -> Runner {
      app.require_subcommand(1);
      auto runners = std::make_shared<std::vector<std::pair<CLI::App*, Runner>>>();
      for (const BenchMode& mode : benchModes()) {
        CLI::App* sub = app.add_subcommand(mode.name, mode.summary);
        runners->emplace_back(sub, mode.configure(*sub));
      }
      return [runners] {
        for (auto& [sub, run] : *runners) {
          if (sub->parsed()) return run();
        }
        return 1;
      };
    },
});

}  // namespace
