#pragma once
// Runs a chain of stages (source -> ... -> sink) over a fixed pool of frame slots: in the caller's
// thread, or on one thread per group of consecutive stages connected by bounded lock-free queues
// (moodycamel), optionally pinned to cores with a real-time scheduling class. Where a stage runs
// never changes what it computes, so every thread layout produces the same results.
//
// Policies: offline replay never drops and keeps order (a full pipeline makes the source wait);
// the live policy drops the oldest frames waiting in front of a stage that can skip frames and
// counts each drop. A stage that throws stops the pipeline: the source stops, frames already past
// the failed stage are finished, everything else is released, and the error names the stage and
// the frame. A stop request (SIGINT/SIGTERM) stops the source and drains the queues.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pipeline/runtime/latency_histogram.h"
#include "pipeline/runtime/stage.h"
#include "platform/realtime/thread_control.h"

namespace voca::pipeline {

// Buffer sizes every slot is allocated with.
struct SlotShape {
  int width = 0, height = 0;
  int max_points = 0;
  int max_landmarks = 0;  // FrameSlot::landmarks_world; 0 when no sink reads them
};

struct PipelineOptions {
  // 1: every stage in the caller's thread. 0: one thread per stage. N > 1: N threads, each running
  // a run of consecutive stages (balanced by Stage::relativeCost()).
  int threads = 0;
  // Stage name -> core (0-based). Stages sharing a thread must not ask for different cores.
  std::vector<std::pair<std::string, int>> pins;
  platform::SchedulingPolicy scheduling = platform::SchedulingPolicy::kOther;
  int priority = 0;          // for the real-time scheduling classes
  bool lock_memory = false;  // mlockall before the first frame
  bool live_policy = false;  // drop the oldest waiting frames instead of waiting
  int live_backlog = 1;      // live policy: frames that may wait in front of a stage that can skip
  int pool_size = 0;         // frame slots; 0: 8 offline, 4 live
  SlotShape slot_shape;
  std::filesystem::path trace_path;  // Chrome trace-event JSON of every frame's stages; empty: none
  // Polled between frames; true stops the source and drains the pipeline.
  std::function<bool()> stop_requested;
};

// The first failure of a stage.
struct StageError {
  std::string stage;
  std::int64_t frame_index = -1;  // -1 when no frame was being handled (start or finish)
  std::string message;
};

// What one stage did over the run. Times are nanoseconds of the monotonic clock.
struct StageReport {
  std::string name;
  int thread = 0;  // index of the thread (group) it ran on
  int core = -1;   // the core it was pinned to, -1 if not pinned
  std::int64_t forwarded = 0;
  std::int64_t dropped = 0;  // live policy, in front of this stage
  std::int64_t damaged = 0;  // released by this stage as undecodable
  std::size_t queue_high_water =
      0;                     // most frames waiting in front of it (0 when it shares the previous stage's thread)
  LatencyHistogram service;  // start to end of its work on a frame
  LatencyHistogram wait;     // end of the previous stage to the start of this one (queueing)
  LatencyHistogram cpu;      // CPU time of its thread for the frame
  // Its helper thread (Stage::helper), empty when it ran none: start to end of the helper's part of a
  // frame, and the helper's CPU time for it.
  LatencyHistogram helper_service;
  LatencyHistogram helper_cpu;
  int helper_core = -1;  // the core the helper was pinned to, -1 if not pinned
};

// A frame that left the pipeline early.
struct ReleasedFrame {
  std::int64_t frame_index = 0;
  std::int64_t time_ns = 0;  // monotonic
  int stage = 0;
  ReleaseReason reason = ReleaseReason::kDropped;
};

struct RunReport {
  std::vector<StageReport> stages;  // source first
  int threads = 1;
  std::int64_t produced = 0;   // frames the source delivered
  std::int64_t completed = 0;  // frames that passed every stage
  std::int64_t dropped = 0;
  std::int64_t damaged = 0;
  // Dropped and damaged frames in the order they left (the first 65536 of them; counts are exact).
  std::vector<ReleasedFrame> released;
  LatencyHistogram end_to_end;  // arrival to the end of the last stage
  std::optional<StageError> error;
  bool stopped = false;  // a stop request ended the run early
  double wall_s = 0.0;
  std::vector<std::string> warnings;  // refused pinning, scheduling or memory locking

  // The report of the stage with this name ("frontend", "backend", ...), or nullptr.
  const StageReport* stage(std::string_view name) const;
};

// Parses a stage-to-core map, "decode:0,frontend:0,backend:1" (stage names as the pipeline reports
// them: read, decode, frontend, backend, write). Throws InputError naming the malformed entry.
std::vector<std::pair<std::string, int>> parseStagePins(std::string_view text);
// The pin-map name of a stage's helper thread (Stage::usesHelper): "<stage>.helper".
std::string helperPinName(std::string_view stage);

class Pipeline {
 public:
  // The stages are used, not owned, and must outlive run(). Throws InputError for an invalid thread
  // layout (unknown stage in pins, conflicting pins in one thread).
  Pipeline(SourceStage& source, std::vector<Stage*> stages, PipelineOptions options);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Runs until the source ends, a stop is requested or a stage fails; returns when every thread has
  // finished. Call once.
  RunReport run();

  // True once a stage failed (any thread, while run() goes on).
  bool failed() const;

  // Which thread (group) each stage runs on, source first.
  const std::vector<int>& threadOfStage() const { return group_of_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<int> group_of_;
};

}  // namespace voca::pipeline
