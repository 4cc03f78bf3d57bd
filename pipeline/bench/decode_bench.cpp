#include "pipeline/bench/decode_bench.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "drivers/decode/decoder_kind.h"
#include "drivers/decode/video_decoder.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca::pipeline {

namespace {

using namespace voca::decode;

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

// Decodes all packets once; returns the number of frames and fills the per-frame vector counts.
int decodeAll(const StreamInfo& stream, const std::vector<Packet>& packets, const DecoderOptions& options,
              DecodedFrame& frame, std::vector<std::vector<MotionBlock>>* vectors) {
  VideoDecoder decoder(stream, options, nullptr, "bench");
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
  for (const Packet& packet : packets) {
    decoder.send(packet);
    take();
  }
  decoder.sendEnd();
  take();
  return frames;
}

bool sameVectors(const std::vector<std::vector<MotionBlock>>& a, const std::vector<std::vector<MotionBlock>>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].size() != b[i].size()) return false;
    for (std::size_t j = 0; j < a[i].size(); ++j) {
      const MotionBlock &p = a[i][j], &q = b[i][j];
      if (p.x != q.x || p.y != q.y || p.w != q.w || p.h != q.h || p.dx != q.dx || p.dy != q.dy) return false;
    }
  }
  return true;
}

}  // namespace

DecodeBenchResult runDecodeBench(const DecodeBenchOptions& opts) {
  if (opts.repeat < 1) throw InputError(fmt::format("--repeat: expected at least 1, got {}", opts.repeat));
  DecodeBenchResult result;
  Demuxer demuxer(opts.video);
  result.stream = demuxer.stream();
  const StreamInfo& stream = result.stream;
  const auto demux_start = std::chrono::steady_clock::now();
  const std::vector<Packet> packets = readAllPackets(demuxer);
  const double demux_s = seconds(std::chrono::steady_clock::now() - demux_start);
  if (packets.empty()) throw InputError(opts.video + ": no video packets");
  std::size_t bytes = 0;
  for (const Packet& p : packets) bytes += p.bytes.size();
  result.packets = packets.size();
  result.stream_fps = stream.frame_rate_num > 0 ? double(stream.frame_rate_num) / stream.frame_rate_den : 0.0;
  result.kbit_per_s = result.stream_fps > 0 ? bytes * 8.0 * result.stream_fps / packets.size() / 1000.0 : 0.0;
  result.demux_packets_per_s = packets.size() / std::max(demux_s, 1e-9);

  std::vector<DecoderOptions> variants(3);
  result.variants.resize(3);
  result.variants[0].label = "full decode + MV export";
  result.variants[1].label = "full decode, no MV export";
  variants[1].export_motion = false;
  result.variants[2].label = "MV-only parse (loop filter skipped)";
  variants[2].decode_pixels = false;
  const DecoderKind kind = parseDecoderKind(opts.decoder);
  for (DecoderOptions& v : variants) {
    v.kind = kind;
    v.log_choice = false;
  }
  result.decoder_description = VideoDecoder(stream, variants[0], nullptr, "bench").description();

  DecodedFrame frame;
  frame.reserve(stream.width, stream.height);
  // Warm-up run of each variant (caches, page faults), also checking that the MV-only parse gives the
  // same vectors as the full decode.
  std::vector<std::vector<MotionBlock>> full_vectors, parse_vectors;
  decodeAll(stream, packets, variants[0], frame, &full_vectors);
  decodeAll(stream, packets, variants[1], frame, nullptr);
  decodeAll(stream, packets, variants[2], frame, &parse_vectors);
  std::size_t num_vectors = 0;
  for (const auto& v : full_vectors) num_vectors += v.size();
  result.parse_vectors_identical = sameVectors(full_vectors, parse_vectors);

  // Variants interleaved per repeat so slow drifts of the machine affect all alike. CPU time of this
  // thread is not inflated when other processes share the cores, so it measures the work itself.
  for (int r = 0; r < opts.repeat; ++r) {
    for (std::size_t v = 0; v < variants.size(); ++v) {
      const auto start = std::chrono::steady_clock::now();
      const std::int64_t cpu_start_ns = platform::threadCpuNs();
      result.frames = decodeAll(stream, packets, variants[v], frame, nullptr);
      const double cpu = 1e-9 * static_cast<double>(platform::threadCpuNs() - cpu_start_ns);
      const double elapsed = seconds(std::chrono::steady_clock::now() - start);
      result.variants[v].wall_fps.push_back(result.frames / std::max(elapsed, 1e-9));
      result.variants[v].cpu_fps.push_back(result.frames / std::max(cpu, 1e-9));
    }
    if (opts.progress) fmt::print(stderr, "\rrepeat {}/{}", r + 1, opts.repeat);
  }
  if (opts.progress) fmt::print(stderr, "\n");
  for (DecodeVariantResult& v : result.variants) {
    v.median_cpu_fps = median(v.cpu_fps);
    v.min_cpu_fps = quantile(v.cpu_fps, 0.0);
    v.max_cpu_fps = quantile(v.cpu_fps, 1.0);
    v.median_wall_fps = median(v.wall_fps);
  }
  result.vectors_per_frame = double(num_vectors) / std::max(1, result.frames);
  return result;
}

}  // namespace voca::pipeline
