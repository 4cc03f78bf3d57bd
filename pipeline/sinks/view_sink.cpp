#include "pipeline/sinks/view_sink.h"

#include <fmt/format.h>
#include <readerwriterqueue/readerwritercircularbuffer.h>

#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

#include "drivers/view/view_page.h"
#include "formats/foxglove/foxglove_schemas.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"

namespace voca::pipeline {

std::unique_ptr<view::FoxgloveServer> startViewServer(const std::string& address, double image_rate_hz,
                                                      std::FILE* announce) {
  if (!(image_rate_hz >= 0.0 && image_rate_hz <= kViewMaxImageRateHz)) {
    throw InputError(
        fmt::format("view image rate {} Hz: expected 0 (no images) to {} Hz", image_rate_hz, kViewMaxImageRateHz));
  }
  const view::ServerAddress parsed = view::parseServerAddress(address);
  view::ServerOptions options;
  options.name = "voca";
  for (const TelemetryChannelInfo& info : telemetryChannels()) {
    const foxglove::Schema& schema = foxglove::schema(info.schema);
    options.channels.push_back({std::string(info.topic), std::string(foxglove::kJsonEncoding), std::string(schema.name),
                                std::string(schema.text), std::string(foxglove::kJsonSchemaEncoding)});
  }
  options.parameters.push_back({"image_rate_hz", image_rate_hz, 0.0, kViewMaxImageRateHz});
  options.page_html = std::string(view::viewPageHtml());
  auto server = std::make_unique<view::FoxgloveServer>(std::move(options));
  server->start(parsed);
  if (announce != nullptr) {
    fmt::print(announce, "view: {} (Foxglove: {})\n", server->pageUrl(), server->websocketUrl());
    std::fflush(announce);
  }
  return server;
}

namespace {

// A frame nobody wants messages of: its pose still joins the paths, for a client that connects later.
struct PoseRecord {
  std::int64_t t_ns = 0;
  SE3d T_world_body;
};

// Poses a run may give while no client subscribes before the view's thread takes them: it looks every
// kIdleWaitUs, so this holds seconds of frames at any camera rate.
constexpr std::size_t kPoseLogCapacity = 4096;
constexpr std::int64_t kIdleWaitUs = 100'000;

}  // namespace

struct ViewSink::Impl {
  using Ring = moodycamel::BlockingReaderWriterCircularBuffer<TelemetrySnapshot*>;

  view::FoxgloveServer& server;
  ViewSinkOptions options;
  std::vector<std::unique_ptr<TelemetrySnapshot>> entries;
  Ring free_entries, filled_entries;
  // Written on the write thread, read by the view's thread only when it wakes anyway: with no client
  // a frame costs an enqueue, not a wake-up of another thread.
  moodycamel::BlockingReaderWriterCircularBuffer<PoseRecord> pose_log{kPoseLogCapacity};
  TelemetryEncoder encoder;
  TelemetryEncoder::Publish publish;
  std::thread worker;
  std::atomic<bool> finishing{false};
  std::atomic<std::int64_t> dropped{0}, published{0};
  // Write thread only: when each rate-limited channel was last asked for (monotonic ns).
  std::int64_t last_image_ns = 0, last_path_ns = 0, last_landmarks_ns = 0;

  Impl(view::FoxgloveServer& s, const ViewSinkOptions& o)
      : server(s),
        options(o),
        free_entries(static_cast<std::size_t>(std::max(o.ring_entries, 1))),
        // Room for every entry and the end marker (nullptr) that finish() adds.
        filled_entries(static_cast<std::size_t>(std::max(o.ring_entries, 1)) + 1),
        encoder(TelemetryOptions{.width = o.width,
                                 .height = o.height,
                                 .max_points = o.max_points,
                                 .max_landmarks = o.max_landmarks,
                                 .ground_truth = o.ground_truth}) {
    for (int i = 0; i < std::max(o.ring_entries, 1); ++i) {
      entries.push_back(std::make_unique<TelemetrySnapshot>());
      entries.back()->reserve(o.width, o.height, o.max_points, o.max_landmarks);
      free_entries.try_enqueue(entries.back().get());
    }
    publish = [this](TelemetryChannel channel, std::int64_t t_ns, std::string_view payload) {
      server.publish(static_cast<std::size_t>(channel), static_cast<std::uint64_t>(std::max<std::int64_t>(t_ns, 0)),
                     payload.data(), payload.size());
    };
  }

  // Whether a channel limited to rate_hz is due, and if so, that it was sent now.
  static bool due(double rate_hz, std::int64_t now_ns, std::int64_t& last_ns) {
    if (!(rate_hz > 0.0)) return false;
    const auto period_ns = static_cast<std::int64_t>(1e9 / rate_hz);
    if (last_ns != 0 && now_ns - last_ns < period_ns) return false;
    last_ns = now_ns;
    return true;
  }

  // Poses of frames that came without a snapshot, in order; they precede any snapshot queued after.
  void takePoses() {
    PoseRecord pose;
    while (pose_log.try_dequeue(pose)) encoder.addPose(pose.t_ns, pose.T_world_body);
  }

  void run() {
    for (;;) {
      TelemetrySnapshot* entry = nullptr;
      if (!filled_entries.wait_dequeue_timed(entry, kIdleWaitUs)) {
        takePoses();
        continue;
      }
      takePoses();
      if (entry == nullptr) return;  // finish(): everything before it is published
      try {
        encoder.encode(*entry, publish);
        ++published;
      } catch (const std::exception& e) {
        // The view must never end the run; a frame it could not show is only logged.
        fmt::print(stderr, "view: frame {} not shown: {}\n", entry->frame_index, e.what());
      }
      free_entries.try_enqueue(entry);
    }
  }
};

ViewSink::ViewSink(view::FoxgloveServer& server, const ViewSinkOptions& options)
    : impl_(std::make_unique<Impl>(server, options)) {}

ViewSink::~ViewSink() { finish(); }

void ViewSink::start() {
  if (!impl_->worker.joinable() && !impl_->finishing.load()) {
    impl_->worker = std::thread([this] { impl_->run(); });
  }
}

void ViewSink::consume(const FrameSlot& slot) {
  Impl& d = *impl_;
  // Every frame's pose goes to the view's thread (the paths grow by it, so a client that connects
  // later still gets the whole path); the rest only when a client wants it, the costly parts when due.
  TelemetryChannels wanted;
  for (const TelemetryChannelInfo& info : telemetryChannels()) {
    wanted.set(channelBit(info.channel), d.server.subscribed(static_cast<std::size_t>(info.channel)));
  }
  if (wanted.none()) {
    if (d.options.stages.backend >= 0 && !d.pose_log.try_enqueue({slot.pose.t_ns, slot.pose.T_world_body})) {
      d.dropped.fetch_add(1, std::memory_order_relaxed);
    }
    return;
  }
  const std::int64_t now = platform::monotonicNs();
  const bool image_due = (wanted.test(channelBit(TelemetryChannel::kImage)) ||
                          wanted.test(channelBit(TelemetryChannel::kMotionVectors))) &&
                         Impl::due(d.server.parameter(kViewImageRateParameter), now, d.last_image_ns);
  if (!image_due) {
    wanted.reset(channelBit(TelemetryChannel::kImage));
    wanted.reset(channelBit(TelemetryChannel::kMotionVectors));
  }
  if ((wanted.test(channelBit(TelemetryChannel::kPath)) ||
       wanted.test(channelBit(TelemetryChannel::kGroundTruthPath))) &&
      !Impl::due(d.options.path_rate_hz, now, d.last_path_ns)) {
    wanted.reset(channelBit(TelemetryChannel::kPath));
    wanted.reset(channelBit(TelemetryChannel::kGroundTruthPath));
  }
  if (wanted.test(channelBit(TelemetryChannel::kLandmarks)) &&
      !Impl::due(d.options.landmarks_rate_hz, now, d.last_landmarks_ns)) {
    wanted.reset(channelBit(TelemetryChannel::kLandmarks));
  }
  TelemetrySnapshot* entry = nullptr;
  if (!d.free_entries.try_dequeue(entry)) {
    d.dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  captureTelemetry(slot, d.options.stages, wanted, *entry);
  entry->view_dropped = d.dropped.load(std::memory_order_relaxed);
  d.filled_entries.try_enqueue(entry);  // never full: it holds at most the ring's entries
}

void ViewSink::finish() {
  Impl& d = *impl_;
  if (d.finishing.exchange(true)) return;
  if (d.worker.joinable()) {
    d.filled_entries.try_enqueue(nullptr);
    d.worker.join();
  }
}

std::int64_t ViewSink::dropped() const { return impl_->dropped.load(); }

std::int64_t ViewSink::published() const { return impl_->published.load(); }

}  // namespace voca::pipeline
