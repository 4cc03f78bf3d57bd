#include "pipeline/sinks/mcap_sink.h"

#include <fmt/format.h>
#include <readerwriterqueue/readerwritercircularbuffer.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

#include "drivers/mcap/mcap_writer.h"
#include "formats/foxglove/foxglove_schemas.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

// What Foxglove shows as the file's writer.
constexpr std::string_view kLibrary = "voca-rt";

// Channels that need a snapshot with room for an image or the landmarks.
TelemetryChannels largeChannels() {
  TelemetryChannels large;
  large.set(channelBit(TelemetryChannel::kImage));
  large.set(channelBit(TelemetryChannel::kMotionVectors));
  large.set(channelBit(TelemetryChannel::kLandmarks));
  return large;
}

// Whether a channel limited to rate_hz is due at the frame time t_ns, and if so, that it was sent then.
// A stamp that goes back (a source that restarted its clock) makes it due again.
struct RateLimit {
  bool sent = false;
  std::int64_t last_ns = 0;

  bool due(double rate_hz, std::int64_t t_ns) {
    if (!(rate_hz > 0.0)) return false;
    const auto period_ns = static_cast<std::int64_t>(1e9 / rate_hz);
    if (sent && t_ns >= last_ns && t_ns - last_ns < period_ns) return false;
    sent = true;
    last_ns = t_ns;
    return true;
  }
};

}  // namespace

struct McapSink::Impl {
  struct Entry {
    TelemetrySnapshot snapshot;
    bool large = false;  // has room for the image and the landmarks
  };
  using Queue = moodycamel::BlockingReaderWriterCircularBuffer<Entry*>;

  McapSinkOptions options;
  mcap::McapWriter writer;
  std::array<std::uint16_t, kTelemetryChannelCount> channel_ids{};  // 0: not recorded
  std::array<std::uint32_t, kTelemetryChannelCount> sequences{};
  std::vector<std::unique_ptr<Entry>> entries;
  Queue free_large, free_small, filled;
  TelemetryEncoder encoder;
  TelemetryEncoder::Publish publish;
  std::thread worker;
  bool finished = false;  // write thread (finish() comes from the sink stage, after the last consume())

  // Set by the recorder's thread when a write failed: consume() then stops copying frames.
  std::atomic<bool> failed{false};
  std::atomic<std::int64_t> dropped{0}, images_skipped{0};
  // Recorder's thread until finish() joins it.
  std::int64_t frames_recorded = 0;
  std::int64_t current_frame = -1;
  std::string failure;

  // Write thread only.
  RateLimit image_limit, path_limit, landmarks_limit;

  explicit Impl(const McapSinkOptions& o)
      : options(o),
        writer(o.file, kLibrary),
        free_large(static_cast<std::size_t>(std::max(o.image_entries, 1))),
        free_small(static_cast<std::size_t>(std::max(o.frame_entries, 1))),
        // Room for every entry and the end marker (nullptr) that finish() adds.
        filled(static_cast<std::size_t>(std::max(o.image_entries, 1) + std::max(o.frame_entries, 1)) + 1),
        encoder(TelemetryOptions{.width = o.width,
                                 .height = o.height,
                                 .max_points = o.max_points,
                                 .max_landmarks = o.max_landmarks,
                                 .ground_truth = o.ground_truth}) {
    addChannels();
    for (int i = 0; i < std::max(o.image_entries, 1); ++i) {
      entries.push_back(std::make_unique<Entry>());
      entries.back()->large = true;
      entries.back()->snapshot.reserve(o.width, o.height, o.max_points, o.max_landmarks);
      free_large.try_enqueue(entries.back().get());
    }
    for (int i = 0; i < std::max(o.frame_entries, 1); ++i) {
      entries.push_back(std::make_unique<Entry>());
      free_small.try_enqueue(entries.back().get());
    }
    publish = [this](TelemetryChannel channel, std::int64_t t_ns, std::string_view payload) {
      const std::size_t c = channelBit(channel);
      if (channel_ids[c] == 0 || !writer.ok()) return;
      // Log and publish time are the frame's own stamp: the trajectory file's time for the same pose.
      const auto t = static_cast<std::uint64_t>(std::max<std::int64_t>(t_ns, 0));
      const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size());
      if (!writer.write(channel_ids[c], sequences[c]++, t, t, bytes)) stop(writer.error());
    };
    if (!writer.ok()) stop(writer.error());
  }

  // One schema record per schema the channels use, then the channels; the ground truth's path only
  // for a run that has one.
  void addChannels() {
    std::array<std::uint16_t, static_cast<std::size_t>(foxglove::SchemaId::kFrameStats) + 1> schema_ids{};
    const bool has_ground_truth = options.ground_truth != nullptr && !options.ground_truth->poses.empty();
    for (const TelemetryChannelInfo& info : telemetryChannels()) {
      if (info.channel == TelemetryChannel::kGroundTruthPath && !has_ground_truth) continue;
      const foxglove::Schema& schema = foxglove::schema(info.schema);
      std::uint16_t& schema_id = schema_ids[static_cast<std::size_t>(info.schema)];
      if (schema_id == 0) schema_id = writer.addSchema(schema.name, foxglove::kJsonSchemaEncoding, schema.text);
      channel_ids[channelBit(info.channel)] = writer.addChannel(schema_id, info.topic, foxglove::kJsonEncoding);
    }
  }

  void stop(const std::string& error) {
    if (failed.exchange(true)) return;
    failure = current_frame < 0 ? fmt::format("MCAP recording stopped before the first frame: {}", error)
                                : fmt::format(
                                      "MCAP recording stopped at frame {}: {}; the file keeps the {} frames "
                                      "recorded before, without the summary at its end",
                                      current_frame, error, frames_recorded);
  }

  void record(const TelemetrySnapshot& snapshot) {
    if (failed.load(std::memory_order_relaxed)) return;
    current_frame = snapshot.frame_index;
    try {
      encoder.encode(snapshot, publish);
    } catch (const std::exception& e) {
      // A frame that cannot be encoded would leave a gap readers could not tell from a lost frame.
      stop(fmt::format("{}: frame {} could not be encoded: {}", options.file.string(), snapshot.frame_index, e.what()));
      return;
    }
    if (writer.ok()) ++frames_recorded;
  }

  void release(Entry* entry) { (entry->large ? free_large : free_small).try_enqueue(entry); }

  void run() {
    for (;;) {
      Entry* entry = nullptr;
      filled.wait_dequeue(entry);    // the recorder's own thread: nothing else waits on it
      if (entry == nullptr) return;  // finish(): everything before it is written
      record(entry->snapshot);
      release(entry);
    }
  }
};

McapSink::McapSink(const McapSinkOptions& options) {
  if (!(options.image_rate_hz >= 0.0 && options.image_rate_hz <= kTelemetryMaxImageRateHz)) {
    throw InputError(fmt::format("MCAP image rate {} Hz: expected 0 (no images) to {} Hz", options.image_rate_hz,
                                 kTelemetryMaxImageRateHz));
  }
  impl_ = std::make_unique<Impl>(options);
}

McapSink::~McapSink() { finish(); }

void McapSink::start() {
  if (!impl_->worker.joinable() && !impl_->finished) impl_->worker = std::thread([this] { impl_->run(); });
}

void McapSink::consume(const FrameSlot& slot) {
  Impl& d = *impl_;
  if (d.finished || d.failed.load(std::memory_order_relaxed)) return;
  const McapSinkOptions& o = d.options;
  const std::int64_t t = slot.frame.t_ns;
  TelemetryChannels wanted;
  wanted.set(channelBit(TelemetryChannel::kPose));
  wanted.set(channelBit(TelemetryChannel::kTransform));
  wanted.set(channelBit(TelemetryChannel::kFrameStats));
  if (d.image_limit.due(o.image_rate_hz, t)) {
    wanted.set(channelBit(TelemetryChannel::kImage));
    wanted.set(channelBit(TelemetryChannel::kMotionVectors));
  }
  if (d.path_limit.due(o.path_rate_hz, t)) {
    wanted.set(channelBit(TelemetryChannel::kPath));
    wanted.set(channelBit(TelemetryChannel::kGroundTruthPath));
  }
  if (o.max_landmarks > 0 && d.landmarks_limit.due(o.landmarks_rate_hz, t)) {
    wanted.set(channelBit(TelemetryChannel::kLandmarks));
  }
  Impl::Entry* entry = nullptr;
  if ((wanted & largeChannels()).any() && !d.free_large.try_dequeue(entry)) {
    // The recorder is still busy with earlier images: this frame goes without its image.
    d.images_skipped.fetch_add(1, std::memory_order_relaxed);
    wanted &= ~largeChannels();
  }
  if (entry == nullptr && !d.free_small.try_dequeue(entry)) {
    d.dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  captureTelemetry(slot, o.stages, wanted, entry->snapshot);
  entry->snapshot.view_dropped = d.dropped.load(std::memory_order_relaxed);
  d.filled.try_enqueue(entry);  // never full: it holds at most every entry
}

void McapSink::finish() {
  Impl& d = *impl_;
  if (d.finished) return;
  d.finished = true;
  if (d.worker.joinable()) {
    d.filled.try_enqueue(nullptr);
    d.worker.join();
  } else {
    // Never started: what consume() queued is written here.
    Impl::Entry* entry = nullptr;
    while (d.filled.try_dequeue(entry)) {
      if (entry != nullptr) d.record(entry->snapshot);
    }
  }
  const bool had_failed = !d.writer.ok();
  if (!d.writer.close() && !had_failed) {
    d.failure = fmt::format(
        "MCAP recording: the summary at the end of the file could not be written: {}; every frame is in the file "
        "(a reader that recovers unclosed files reads it)",
        d.writer.error());
  }
}

std::int64_t McapSink::dropped() const { return impl_->dropped.load(); }

std::int64_t McapSink::imagesSkipped() const { return impl_->images_skipped.load(); }

std::int64_t McapSink::framesRecorded() const { return impl_->frames_recorded; }

std::uint64_t McapSink::messagesWritten() const { return impl_->writer.messageCount(); }

const std::string& McapSink::failure() const { return impl_->failure; }

}  // namespace voca::pipeline
