#pragma once
// A recording of a run (`--mcap out.mcap`): the live view's telemetry channels (pipeline/sinks/telemetry.h)
// written to an MCAP file as the run goes, for Foxglove or Lichtblick to replay. On the pipeline's write
// thread consume() only copies the frame into a free snapshot and hands it to the recorder's own thread
// through a bounded lock-free queue; with no free snapshot the frame's messages are dropped and counted,
// never waited for. The recorder's thread encodes (JPEG, JSON) and writes (drivers/mcap).
//
// Every frame gives its pose, transform and statistics; the path (and the ground truth's) and the window's
// landmarks come at rates of their own, the camera image and its motion vectors at image_rate_hz, all
// counted in the frames' own time, so a recording made faster than real time replays like one made at
// the camera's pace. Snapshots with room for an image are few; when they are all taken, a frame that was
// due an image is recorded without it rather than not at all.
//
// A failed write (a full disk) stops the recording: what was written stays readable (the writer hands
// each record to the OS as it comes), the run goes on unaffected, and failure() says what happened, once,
// for the run's warnings. finish() writes the summary and the footer and closes the file, also after a
// stop (SIGINT ends the run cleanly, then the sinks finish).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "pipeline/sinks/sink_stage.h"
#include "pipeline/sinks/telemetry.h"

namespace voca::pipeline {

struct McapSinkOptions {
  std::filesystem::path file;
  int width = 0, height = 0;  // of the frames
  int max_points = 0;         // per camera
  int max_landmarks = 0;      // FrameSlot::landmarks_world's capacity
  StagePositions stages;
  const Trajectory* ground_truth = nullptr;  // copied; nullptr: no ground truth channel
  // Per second of the frames' time. Images: 0 (none) to kTelemetryMaxImageRateHz.
  double image_rate_hz = kTelemetryDefaultImageRateHz;
  double path_rate_hz = 1.0;  // a path message holds the whole path so far: the file's largest
  double landmarks_rate_hz = 5.0;
  int image_entries = 4;  // snapshots with room for an image and the landmarks
  // Snapshots of the scalars only (pose, statistics): seconds of frames at any camera rate, so only
  // a recorder stalled that long (a disk that hangs) loses frames.
  int frame_entries = 512;
};

class McapSink final : public FrameSink {
 public:
  // Creates the file and writes its header, schemas and channels; allocates every snapshot and the
  // encoder. Throws InputError naming the file when it cannot be created, or for an image rate outside
  // 0 to kTelemetryMaxImageRateHz. A header that cannot be written (/dev/full) is a failure() like any
  // later write: the run goes on. start() launches the recorder's thread.
  explicit McapSink(const McapSinkOptions& options);
  ~McapSink() override;  // finish()
  void start();
  // Write thread: copies what the frame's due channels need and queues it; never waits, never allocates.
  void consume(const FrameSlot& slot) override;
  // Writes what the queue still holds (bounded: the queued snapshots' work), then the summary and the
  // footer, and closes the file. Once; later calls do nothing.
  void finish() override;
  FrameSinkNeeds needs() const override { return {.left_traces = true, .landmarks = true}; }

  // After finish(): frames whose messages were dropped because the recorder's queue was full, frames
  // recorded without the image they were due for the same reason, frames written, messages written.
  std::int64_t dropped() const;
  std::int64_t imagesSkipped() const;
  std::int64_t framesRecorded() const;
  std::uint64_t messagesWritten() const;
  // After finish(): empty when everything was written; else one sentence naming the file, the frame at
  // which the recording stopped and the OS error.
  const std::string& failure() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::pipeline
