#include "pipeline/bench/decode_bench.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>

#include "drivers/decode/decoder_kind.h"
#include "drivers/decode/video_decoder.h"
#include "drivers/encode/dataset_encoder.h"
#include "formats/dataset/dataset.h"
#include "platform/realtime/clock.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca::pipeline {

namespace {

using namespace voca::decode;

// FNV-1a, 64 bit: a hash of every decoded luma byte, to compare two decodes without keeping them.
constexpr std::uint64_t kFnvOffsetBasis = 0xcbf29ce484222325ull, kFnvPrime = 0x100000001b3ull;

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

// One camera's packets, read before timing.
struct CameraPackets {
  StreamInfo stream;
  std::vector<Packet> packets;
};

// Decodes every camera's packets once, frame k of all cameras together, and returns the number of
// frames (of the first camera). frame_cpu_ms (if given) gets this thread's CPU time per frame;
// vectors (if given) every camera frame's motion vectors, camera by camera within a frame.
// luma_hash (if given), an FNV-1a state, takes in every luma plane decoded, in order.
int decodeAll(const std::vector<CameraPackets>& cameras, const DecoderOptions& options, DecodedFrame& frame,
              std::vector<double>* frame_cpu_ms, std::vector<std::vector<MotionBlock>>* vectors,
              std::uint64_t* luma_hash = nullptr) {
  std::vector<std::unique_ptr<VideoDecoder>> decoders;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    decoders.push_back(
        std::make_unique<VideoDecoder>(cameras[c].stream, options, nullptr, fmt::format("bench cam{}", c)));
  }
  int frames = 0;
  auto take = [&](std::size_t c) {
    while (decoders[c]->receive(frame)) {
      if (c == 0) ++frames;
      if (luma_hash != nullptr) {
        for (int y = 0; y < frame.luma.height(); ++y) {
          const std::uint8_t* row = frame.luma.row(y);
          for (int x = 0; x < frame.luma.width(); ++x) *luma_hash = (*luma_hash ^ row[x]) * kFnvPrime;
        }
      }
      if (vectors != nullptr) {
        const auto blocks = frame.motion.blocks();
        vectors->emplace_back(blocks.begin(), blocks.end());
      }
    }
  };
  const std::size_t count = cameras[0].packets.size();
  for (std::size_t k = 0; k < count; ++k) {
    const std::int64_t start_ns = platform::threadCpuNs();
    for (std::size_t c = 0; c < cameras.size(); ++c) {
      decoders[c]->send(cameras[c].packets[k]);
      take(c);
    }
    if (frame_cpu_ms != nullptr)
      frame_cpu_ms->push_back(1e-6 * static_cast<double>(platform::threadCpuNs() - start_ns));
  }
  // Frames the decoders still hold (none for the paper's streams, which have no B-frames) count
  // towards the last frame.
  const std::int64_t flush_start_ns = platform::threadCpuNs();
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    decoders[c]->sendEnd();
    take(c);
  }
  if (frame_cpu_ms != nullptr && !frame_cpu_ms->empty()) {
    frame_cpu_ms->back() += 1e-6 * static_cast<double>(platform::threadCpuNs() - flush_start_ns);
  }
  return frames;
}

// The videos to decode together: both cameras of a VOCA video folder, or the one file given; for a
// folder also the rate its frames were recorded at (0 when its data.csv cannot tell).
std::vector<std::filesystem::path> benchVideos(const std::filesystem::path& input, double& recording_fps) {
  recording_fps = 0.0;
  if (!std::filesystem::is_directory(input)) return {input};
  const Dataset dataset = openDataset(input);
  if (dataset.layout != DatasetLayout::kVocaVideo) {
    throw InputError(
        fmt::format("{} is a {} image folder; voca bench decode needs a video file or a VOCA video "
                    "folder (voca encode makes one)",
                    input.string(), layoutName(dataset.layout)));
  }
  if (dataset.frames.size() >= 2) {
    int fps_num = 0, fps_den = 1;
    try {
      encode::datasetFrameRate(dataset, fps_num, fps_den);
      recording_fps = double(fps_num) / fps_den;
    } catch (const InputError&) {
      // Timestamps that do not increase: the rate stays unknown, the benchmark itself is unaffected.
    }
  }
  return {dataset.video_left, dataset.video_right};
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
  result.videos = benchVideos(opts.input, result.recording_fps);
  std::vector<CameraPackets> cameras;
  const auto demux_start = std::chrono::steady_clock::now();
  for (const std::filesystem::path& video : result.videos) {
    Demuxer demuxer(video.string());
    CameraPackets& camera = cameras.emplace_back();
    camera.stream = demuxer.stream();
    camera.packets = readAllPackets(demuxer);
    if (camera.packets.empty()) throw InputError(video.string() + ": no video packets");
    const StreamInfo& first = cameras[0].stream;
    if (camera.stream.codec_name != first.codec_name || camera.stream.width != first.width ||
        camera.stream.height != first.height || camera.packets.size() != cameras[0].packets.size()) {
      throw InputError(fmt::format("{}: {} {}x{} with {} packets, but {} is {} {}x{} with {}; the cameras must match",
                                   video.string(), camera.stream.codec_name, camera.stream.width, camera.stream.height,
                                   camera.packets.size(), result.videos[0].string(), first.codec_name, first.width,
                                   first.height, cameras[0].packets.size()));
    }
  }
  const double demux_s = seconds(std::chrono::steady_clock::now() - demux_start);
  result.stream = cameras[0].stream;
  const StreamInfo& stream = result.stream;
  std::size_t bytes = 0;
  for (const CameraPackets& camera : cameras) {
    for (const Packet& p : camera.packets) bytes += p.bytes.size();
  }
  result.packets = cameras[0].packets.size();
  const double all_packets = static_cast<double>(result.packets * cameras.size());
  result.stream_fps = stream.frame_rate_num > 0 ? double(stream.frame_rate_num) / stream.frame_rate_den : 0.0;
  result.kbit_per_s = result.stream_fps > 0 ? bytes * 8.0 * result.stream_fps / all_packets / 1000.0 : 0.0;
  result.recording_kbit_per_s =
      result.recording_fps > 0 ? bytes * 8.0 * result.recording_fps / all_packets / 1000.0 : 0.0;
  result.demux_packets_per_s = all_packets / std::max(demux_s, 1e-9);

  // A libavcodec that can skip the chroma planes does so in every variant above; the fifth decodes
  // them too, for the saving and to check that the luma planes are the same either way.
  result.luma_only = lumaOnlyDecodingAvailable();
  const std::size_t num_variants = result.luma_only ? 5 : 4;
  std::vector<DecoderOptions> variants(num_variants);
  result.variants.resize(num_variants);
  result.variants[0].label = "full decode + MV export";
  result.variants[1].label = "full decode, no MV export";
  variants[1].export_motion = false;
  result.variants[2].label = "MV-only parse (loop filter skipped)";
  variants[2].decode_pixels = false;
  // The opt-in `--skip-deblock` of voca run: pictures inexact, vectors exact (checked below).
  result.variants[3].label = "full + MV, deblocking skipped (opt-in)";
  variants[3].skip_loop_filter = true;
  if (result.luma_only) {
    result.variants[4].label = "full + MV, chroma decoded too";
    variants[4].luma_only = false;
  }
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
  std::vector<std::vector<MotionBlock>> full_vectors, parse_vectors, unfiltered_vectors;
  std::uint64_t luma_hash = kFnvOffsetBasis;
  decodeAll(cameras, variants[0], frame, nullptr, &full_vectors, &luma_hash);
  if (result.luma_only) {
    std::uint64_t chroma_too_hash = kFnvOffsetBasis;
    decodeAll(cameras, variants[4], frame, nullptr, nullptr, &chroma_too_hash);
    result.luma_only_identical = luma_hash == chroma_too_hash;
  }
  decodeAll(cameras, variants[1], frame, nullptr, nullptr);
  decodeAll(cameras, variants[2], frame, nullptr, &parse_vectors);
  decodeAll(cameras, variants[3], frame, nullptr, &unfiltered_vectors);
  std::size_t num_vectors = 0;
  for (const auto& v : full_vectors) num_vectors += v.size();
  result.parse_vectors_identical =
      sameVectors(full_vectors, parse_vectors) && sameVectors(full_vectors, unfiltered_vectors);

  // Variants interleaved per repeat so slow drifts of the machine affect all alike. CPU time of this
  // thread is not inflated when other processes share the cores, so it measures the work itself.
  for (DecodeVariantResult& v : result.variants) v.frame_cpu_ms.reserve(result.packets * opts.repeat);
  platform::ProgressLine progress;
  for (int r = 0; r < opts.repeat; ++r) {
    for (std::size_t v = 0; v < variants.size(); ++v) {
      const auto start = std::chrono::steady_clock::now();
      result.frames = decodeAll(cameras, variants[v], frame, &result.variants[v].frame_cpu_ms, nullptr);
      const double elapsed = seconds(std::chrono::steady_clock::now() - start);
      result.variants[v].run_wall_fps.push_back(result.frames / std::max(elapsed, 1e-9));
    }
    if (opts.progress) progress.update("repeat {}/{}", r + 1, opts.repeat);
  }
  progress.end();
  for (DecodeVariantResult& v : result.variants) {
    v.median_ms = median(v.frame_cpu_ms);
    v.p99_ms = quantile(v.frame_cpu_ms, 0.99);
    double total_ms = 0.0;
    for (double ms : v.frame_cpu_ms) total_ms += ms;
    v.mean_ms = total_ms / static_cast<double>(std::max<std::size_t>(1, v.frame_cpu_ms.size()));
    v.cpu_fps = 1000.0 / std::max(v.mean_ms, 1e-9);
    v.median_wall_fps = median(v.run_wall_fps);
  }
  const double camera_frames = static_cast<double>(std::max<std::size_t>(1, full_vectors.size()));
  result.vectors_per_frame = double(num_vectors) / camera_frames;
  return result;
}

}  // namespace voca::pipeline
