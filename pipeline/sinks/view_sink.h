#pragma once
// The live view (`--view`): a sink that feeds a run's telemetry (pipeline/sinks/telemetry.h) to a
// Foxglove WebSocket server (drivers/view), which also serves the built-in page. On the pipeline's
// write thread consume() only copies what subscribed channels need into a free entry of a small ring
// and hands it to the view's own thread through a bounded lock-free queue; with no free entry the
// update is dropped and counted. That thread draws the tracks, encodes JPEG and JSON and publishes;
// the server never waits for a client. With no client subscribed, consume() only logs the pose (the
// path a later client gets) in a queue the view's thread empties when it wakes, every 100 ms. The
// image channel (the expensive one) is drawn and encoded only while a client subscribes, at most
// image_rate_hz times a second (a parameter clients may set).

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "drivers/view/foxglove_server.h"
#include "pipeline/sinks/sink_stage.h"
#include "pipeline/sinks/telemetry.h"

namespace voca::pipeline {

// The server's parameters (the protocol's "parameters" capability), by index.
inline constexpr std::size_t kViewImageRateParameter = 0;  // "image_rate_hz"
inline constexpr double kViewDefaultImageRateHz = kTelemetryDefaultImageRateHz;
inline constexpr double kViewMaxImageRateHz = kTelemetryMaxImageRateHz;

// Starts the view's server on "[host:]port" with the telemetry channels, the built-in page and the
// image rate parameter, and prints once where to open it ("view: http://host:port/ (Foxglove:
// ws://host:port)") to announce (nullptr: nowhere). Throws InputError when the address cannot be
// bound (naming it and what to do) or the rate is outside 0 to kViewMaxImageRateHz.
std::unique_ptr<view::FoxgloveServer> startViewServer(const std::string& address, double image_rate_hz,
                                                      std::FILE* announce);

struct ViewSinkOptions {
  int width = 0, height = 0;  // of the frames
  int max_points = 0;         // per camera
  int max_landmarks = 0;      // FrameSlot::landmarks_world's capacity
  StagePositions stages;
  const Trajectory* ground_truth = nullptr;  // copied; nullptr: none
  int ring_entries = 4;
  // Channels sent at a rate of their own (the server's parameter sets the image's).
  double path_rate_hz = 4.0;
  double landmarks_rate_hz = 5.0;
};

class ViewSink final : public FrameSink {
 public:
  // Allocates everything (ring, JPEG encoder, buffers); start() launches the view's thread.
  ViewSink(view::FoxgloveServer& server, const ViewSinkOptions& options);
  ~ViewSink() override;  // finish()
  void start();
  void consume(const FrameSlot& slot) override;
  // Publishes what the ring still holds and joins the view's thread (bounded: a few frames' work).
  void finish() override;
  FrameSinkNeeds needs() const override { return {.left_traces = true, .landmarks = true}; }

  // Updates dropped because the view's thread had no free ring entry.
  std::int64_t dropped() const;
  // Snapshots the view's thread turned into messages.
  std::int64_t published() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::pipeline
