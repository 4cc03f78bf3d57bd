// `voca bench <mode>`: throughput measurements on this machine, and evaluation suites. Each mode is one entry of kModes
// below (a name, a summary and a configure function declaring its options), so a new mode is one
// function plus one row.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <fmt/core.h>

#include "drivers/decode/video_decoder.h"
#include "platform/realtime/clock.h"
#include "tools/voca/bench_backend.h"
#include "tools/voca/bench_frontend.h"
#include "tools/voca/bench_pipeline.h"
#include "tools/voca/bench_suite.h"
#include "tools/voca/command.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace {

using voca::cli::Runner;

// One `voca bench` sub-mode.
struct BenchMode {
  const char* name;
  const char* summary;
  std::function<Runner(CLI::App&)> configure;
};

// ---- shared helpers -------------------------------------------------------------------------

std::string cpuModel() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  // x86 says "model name", most ARM kernels "Model" or "Hardware".
  for (const char* key : {"model name", "Model", "Hardware"}) {
    cpuinfo.clear();
    cpuinfo.seekg(0);
    while (std::getline(cpuinfo, line)) {
      if (line.rfind(key, 0) != 0) continue;
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos && colon + 2 <= line.size()) return line.substr(colon + 2);
    }
  }
  return "unknown CPU";
}

void printMachine() {
  fmt::print("machine: {} ({} hardware threads); measured on one thread\n", cpuModel(),
             std::thread::hardware_concurrency());
}

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

// Wall and CPU time of one timed section, as rates.
struct RateSamples {
  std::vector<double> wall_fps, cpu_fps;
};

// ---- decode ---------------------------------------------------------------------------------

struct DecodeBenchOptions {
  std::string video;
  int repeat = 5;
  std::string decoder = "software";
};

struct DecodeVariant {
  const char* label;
  voca::decode::DecoderOptions options;
};

// Decodes all packets once; returns the number of frames and fills the per-frame vector counts.
int decodeAll(const voca::decode::StreamInfo& stream, const std::vector<voca::decode::Packet>& packets,
              const voca::decode::DecoderOptions& options, voca::decode::DecodedFrame& frame,
              std::vector<std::vector<voca::MotionBlock>>* vectors) {
  voca::decode::VideoDecoder decoder(stream, options, nullptr, "bench");
  int frames = 0;
  auto take = [&] {
    while (decoder.receive(frame)) {
      ++frames;
      if (vectors != nullptr) {
        const auto blocks = frame.motion.blocks();
        vectors->emplace_back(blocks.begin(), blocks.end());
      }
    }
  };
  for (const voca::decode::Packet& packet : packets) {
    decoder.send(packet);
    take();
  }
  decoder.sendEnd();
  take();
  return frames;
}

bool sameVectors(const std::vector<std::vector<voca::MotionBlock>>& a,
                 const std::vector<std::vector<voca::MotionBlock>>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].size() != b[i].size()) return false;
    for (std::size_t j = 0; j < a[i].size(); ++j) {
      const voca::MotionBlock &p = a[i][j], &q = b[i][j];
      if (p.x != q.x || p.y != q.y || p.w != q.w || p.h != q.h || p.dx != q.dx || p.dy != q.dy) return false;
    }
  }
  return true;
}

int runDecodeBench(const DecodeBenchOptions& opts) {
  using namespace voca::decode;
  if (opts.repeat < 1) throw voca::InputError("--repeat: expected at least 1, got " + std::to_string(opts.repeat));
  Demuxer demuxer(opts.video);
  const StreamInfo stream = demuxer.stream();
  const auto demux_start = std::chrono::steady_clock::now();
  const std::vector<Packet> packets = readAllPackets(demuxer);
  const double demux_s = seconds(std::chrono::steady_clock::now() - demux_start);
  if (packets.empty()) throw voca::InputError(opts.video + ": no video packets");
  std::size_t bytes = 0;
  for (const Packet& p : packets) bytes += p.bytes.size();
  const double fps_stream = stream.frame_rate_num > 0 ? double(stream.frame_rate_num) / stream.frame_rate_den : 0.0;

  printMachine();
  fmt::print(
      "video: {} ({}, {}x{}, {} packets, {:.0f} kbit/s at {:.4g} fps); demux {:.0f} packets/s (not timed below)\n",
      opts.video, stream.codec_name, stream.width, stream.height, packets.size(),
      fps_stream > 0 ? bytes * 8.0 * fps_stream / packets.size() / 1000.0 : 0.0, fps_stream,
      packets.size() / std::max(demux_s, 1e-9));

  std::vector<DecodeVariant> variants(3);
  variants[0].label = "full decode + MV export";
  variants[1].label = "full decode, no MV export";
  variants[1].options.export_motion = false;
  variants[2].label = "MV-only parse (loop filter skipped)";
  variants[2].options.decode_pixels = false;
  const DecoderBackend backend = parseBackend(opts.decoder);
  for (DecodeVariant& v : variants) {
    v.options.backend = backend;
    v.options.log_choice = false;
  }
  {
    // The backend actually used (auto may fall back), logged once.
    const VideoDecoder probe(stream, variants[0].options, nullptr, "bench");
    fmt::print("{}\n", probe.description());
  }

  DecodedFrame frame;
  frame.reserve(stream.width, stream.height);
  // Warm-up run of each variant (caches, page faults), also checking that the MV-only parse gives the
  // same vectors as the full decode.
  std::vector<std::vector<voca::MotionBlock>> full_vectors, parse_vectors;
  decodeAll(stream, packets, variants[0].options, frame, &full_vectors);
  decodeAll(stream, packets, variants[1].options, frame, nullptr);
  decodeAll(stream, packets, variants[2].options, frame, &parse_vectors);
  std::size_t num_vectors = 0;
  for (const auto& v : full_vectors) num_vectors += v.size();

  // Variants interleaved per repeat so slow drifts of the machine affect all alike.
  std::vector<RateSamples> fps(variants.size());
  int frames = 0;
  for (int r = 0; r < opts.repeat; ++r) {
    for (std::size_t v = 0; v < variants.size(); ++v) {
      const auto start = std::chrono::steady_clock::now();
      const std::int64_t cpu_start_ns = voca::platform::threadCpuNs();
      frames = decodeAll(stream, packets, variants[v].options, frame, nullptr);
      const double cpu = 1e-9 * static_cast<double>(voca::platform::threadCpuNs() - cpu_start_ns);
      const double elapsed = seconds(std::chrono::steady_clock::now() - start);
      fps[v].wall_fps.push_back(frames / std::max(elapsed, 1e-9));
      fps[v].cpu_fps.push_back(frames / std::max(cpu, 1e-9));
    }
    fmt::print(stderr, "\rrepeat {}/{}", r + 1, opts.repeat);
  }
  fmt::print(stderr, "\n");

  fmt::print(
      "{} frames per run, {} runs per variant, medians (fps from this thread's CPU time; wall-clock fps\n"
      "also shown, lower when other processes share the cores):\n",
      frames, opts.repeat);
  std::vector<double> med(variants.size());
  for (std::size_t v = 0; v < variants.size(); ++v) {
    med[v] = voca::median(fps[v].cpu_fps);
    const auto [lo, hi] = std::minmax_element(fps[v].cpu_fps.begin(), fps[v].cpu_fps.end());
    fmt::print("  {:<38} {:7.0f} fps  {:6.3f} ms/frame  (min {:.0f}, max {:.0f}; wall {:.0f} fps)\n", variants[v].label,
               med[v], 1000.0 / med[v], *lo, *hi, voca::median(fps[v].wall_fps));
  }
  const double overhead_ms = 1000.0 / med[0] - 1000.0 / med[1];
  fmt::print("  MV extraction overhead: {:+.3f} ms/frame ({:+.1f} %), {:.0f} vectors per frame\n", overhead_ms,
             100.0 * overhead_ms / (1000.0 / med[1]), double(num_vectors) / std::max<std::size_t>(1, frames));
  fmt::print("  MV-only parse vectors identical to full decode: {}\n",
             sameVectors(full_vectors, parse_vectors) ? "yes" : "NO");
  fmt::print("  targets (752x480, 500 kbit/s, one core): full + MV >= 1200 fps: {}; MV-only >= 1800 fps: {}\n",
             med[0] >= 1200 ? "met" : "not met", med[2] >= 1800 ? "met" : "not met");
  if (stream.width != 752 || stream.height != 480) {
    fmt::print("  (this video is {}x{}, so the targets are only indicative)\n", stream.width, stream.height);
  }
  return 0;
}

Runner configureDecodeBench(CLI::App& app) {
  auto opts = std::make_shared<DecodeBenchOptions>();
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
  return [opts] { return runDecodeBench(*opts); };
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
