#include "pipeline/stream/stream_runner.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <thread>
#include <vector>

#include <fmt/core.h>

#include "drivers/network/frame_stamp.h"
#include "drivers/network/ts_writer.h"
#include "drivers/source/dataset_source.h"
#include "drivers/source/network_source.h"
#include "formats/dataset/dataset.h"
#include "platform/filesystem/output_paths.h"
#include "platform/realtime/clock.h"
#include "platform/realtime/stop_signal.h"
#include "voca/core/error.h"
#include "voca/core/quantile.h"

namespace voca::pipeline {

namespace {

// A URL that names a file (out.ts, file:///tmp/out.ts) is an output like `voca run -o`: it must not be
// a file of the dataset being sent or lie in its folders (`voca stream seq seq/mav0/cam0/data.csv`
// replaced the frame list with the stream), and its folder must exist, before anything is encoded.
void requireOutputFileApart(const std::string& url, const Dataset& dataset) {
  if (isStreamUrl(url) && !isRecordedStreamUrl(url)) return;  // udp://, tcp://, ...: nothing on disk
  const NamedPath output{"the output file",
                         isRecordedStreamUrl(url) ? recordedStreamFile(url) : std::filesystem::path(url)};
  std::vector<NamedPath> inputs = datasetReadPaths(dataset);
  if (dataset.calibration) inputs.push_back({"the dataset's calibration", *dataset.calibration});
  requireOutputsApart(std::span(&output, 1), inputs);
  requireWritableFile(output);
}

}  // namespace

StreamResult runStream(const StreamOptions& options) {
  if (!(options.speed > 0.0))
    throw InputError(fmt::format("--speed: expected a positive factor, got {}", options.speed));
  const std::function<bool()> stop_requested =
      options.stop_requested ? options.stop_requested : std::function<bool()>(platform::stopRequested);
  const Dataset dataset = openDataset(options.input);
  if (dataset.layout == DatasetLayout::kVocaVideo) {
    throw InputError(
        fmt::format("{}: a VOCA video folder is already encoded; `voca stream` encodes a raw dataset "
                    "(image folders) live, as a camera would",
                    options.input.string()));
  }
  requireOutputFileApart(options.url, dataset);
  ReplayOptions replay;
  replay.max_frames = options.max_frames;
  std::unique_ptr<StereoSource> source = openDatasetSource(dataset, replay);
  const SourceInfo& info = source->info();

  encode::LiveEncoderSettings live = options.encoder;
  const double rate = info.nominal_rate_hz > 0.0 ? info.nominal_rate_hz : 20.0;
  encode::setFrameRate(live, rate);
  encode::silenceCodecLogs();
  std::array<encode::VideoEncoder, 2> encoders;
  StreamResult result;
  result.description = info.description;
  const encode::EncoderChoice choice = encode::openLiveEncoder(encoders[0], live, info.width, info.height);
  live.kind = choice.kind;  // the right camera on the same encoder
  encode::openLiveEncoder(encoders[1], live, info.width, info.height);
  result.encoder_description = choice.description;
  std::fprintf(stderr, "%s\n", choice.description.c_str());

  std::optional<network::StereoTsWriter> opened;
  try {
    opened.emplace(options.url, encoders[0].width(), encoders[0].height(), stop_requested);
  } catch (const InputError&) {
    if (!stop_requested()) throw;
    result.stop_signal = platform::stopSignal();  // Ctrl-C while a tcp:// listener waits: a clean stop
    return result;
  }
  network::StereoTsWriter& writer = *opened;
  if (options.progress) {
    std::fprintf(stderr, "streaming %s to %s at %.4g Hz x %.3g\n", info.description.c_str(), options.url.c_str(), rate,
                 options.speed);
  }

  RawStereoFrame frame;
  std::vector<std::uint8_t> stamped;
  std::vector<double> encode_ms;
  encode_ms.reserve(static_cast<std::size_t>(std::max<std::int64_t>(info.expected_frames, 0)));
  const auto period_ns = static_cast<std::int64_t>(1e9 / rate / options.speed);
  std::int64_t origin_t_ns = 0, origin_mono = 0;
  while (source->next(frame)) {
    if (stop_requested()) break;
    if (result.frames == 0) {
      origin_t_ns = frame.t_ns;
      origin_mono = platform::monotonicNs();
    }
    // The recording's own pace: frame i goes out (t_i - t_0) / speed after frame 0 did.
    const auto due =
        origin_mono + static_cast<std::int64_t>(static_cast<double>(frame.t_ns - origin_t_ns) / options.speed);
    bool stopped = false;
    for (std::int64_t left = due - platform::monotonicNs(); left > 0; left = due - platform::monotonicNs()) {
      if ((stopped = stop_requested())) break;
      std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<std::int64_t>(left, 5'000'000)));
    }
    if (stopped) break;
    const std::int64_t start = platform::monotonicNs();
    if (start - due > period_ns) ++result.late_frames;
    for (std::size_t c = 0; c < 2; ++c) {
      const auto packets = encoders[c].encode(frame.images[c].view(), frame.frame_index);
      for (const encode::EncodedPacket& packet : packets) {
        network::stampAccessUnit(packet.bytes, {frame.t_ns, frame.frame_index}, stamped);
        writer.write(static_cast<int>(c), stamped, frame.t_ns, packet.keyframe);
        result.bytes += static_cast<std::int64_t>(packet.bytes.size());
      }
    }
    encode_ms.push_back(static_cast<double>(platform::monotonicNs() - start) * 1e-6);
    ++result.frames;
    if (options.progress && result.frames % 100 == 0) {
      std::fprintf(stderr, "sent %lld frames (%.1f s)\n", static_cast<long long>(result.frames),
                   static_cast<double>(platform::monotonicNs() - origin_mono) * 1e-9);
    }
  }
  writer.finish();
  if (result.frames > 0) result.seconds = static_cast<double>(platform::monotonicNs() - origin_mono) * 1e-9;
  result.recorded_seconds = static_cast<double>(result.frames) / rate;
  result.encode_ms_p50 = quantileInPlace(encode_ms, 0.5);
  result.encode_ms_p99 = quantileInPlace(encode_ms, 0.99);
  result.encode_ms_max = encode_ms.empty() ? 0.0 : *std::max_element(encode_ms.begin(), encode_ms.end());
  if (stop_requested()) result.stop_signal = platform::stopSignal();
  return result;
}

void printStreamSummary(const StreamResult& r, std::FILE* out) {
  // The video's bitrate is over the recording's time: at --speed 50 the same bytes go out 50 times faster.
  fmt::print(out, "sent: {} stereo frames ({:.1f} s of recording) in {:.1f} s, video {:.0f} kbit/s per camera ({})\n",
             r.frames, r.recorded_seconds, r.seconds,
             r.recorded_seconds > 0 ? static_cast<double>(r.bytes) * 8.0 / r.recorded_seconds / 2.0 / 1000.0 : 0.0,
             r.encoder_description);
  fmt::print(out, "encode per stereo frame: p50 {:.1f} ms, p99 {:.1f} ms, max {:.1f} ms; {} frames sent late\n",
             r.encode_ms_p50, r.encode_ms_p99, r.encode_ms_max, r.late_frames);
}

}  // namespace voca::pipeline
