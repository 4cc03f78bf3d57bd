#pragma once
// The last stage: hands every finished frame to the sinks (trajectory file, statistics, overlay
// video, progress), in frame order, on one thread.

#include <vector>

#include "pipeline/runtime/stage.h"

namespace voca::pipeline {

// Where each stage sits in the pipeline (the source is 0): the index of its StageTiming in a
// FrameSlot. -1 for a stage the run does not have.
struct StagePositions {
  int encode = -1, decode = -1, frontend = -1, backend = -1, write = -1;
};

// What a sink reads of a frame beyond what every run fills (images, tracks, pose, timings): the
// stages copy these only when a sink asks, so runs without such a sink pay nothing for them.
struct FrameSinkNeeds {
  bool left_traces = false;  // FrameSlot::left_traces
  bool landmarks = false;    // FrameSlot::landmarks_world
};

// A consumer of finished frames. begin() is called once before the first frame with where the stages
// are; consume() once per frame in order; finish() once at the end (also after a stop or a failure),
// and writes what the sink still holds.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void begin(const StagePositions& /*positions*/) {}
  virtual void consume(const FrameSlot& slot) = 0;
  virtual void finish() {}
  // Asked once, before the run starts.
  virtual FrameSinkNeeds needs() const { return {}; }
};

class SinkStage final : public Stage {
 public:
  explicit SinkStage(std::vector<FrameSink*> sinks) : sinks_(std::move(sinks)) {}
  std::string_view name() const override { return "write"; }
  void process(FrameSlot& slot, Emitter& out) override {
    for (FrameSink* sink : sinks_) sink->consume(slot);
    out.forward(slot);
  }
  void finish(Emitter& /*out*/) override {
    for (FrameSink* sink : sinks_) sink->finish();
  }

 private:
  std::vector<FrameSink*> sinks_;
};

}  // namespace voca::pipeline
