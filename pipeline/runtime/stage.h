#pragma once
// The stages of the pipeline and how they hand frames on. A stage computes; the runner decides on
// which thread it runs and what happens between stages (queues, back-pressure, drops), so a
// pipelined run computes exactly what a single-threaded one does.
//
// Lifecycle: constructing a stage allocates what it needs; start() runs once on the thread that
// will run the stage (warm-up allocations belong there); process() handles one frame; finish() runs
// once at the end of the stream and emits what the stage still holds.

#include <cstdint>
#include <string_view>

#include "pipeline/runtime/frame_slot.h"

namespace voca::pipeline {

class StageHelper;

// Why a slot leaves the pipeline before its last stage.
enum class ReleaseReason : std::uint8_t {
  kDone,        // passed every stage
  kDropped,     // the live policy dropped it: a later frame was waiting
  kDamaged,     // its data could not be decoded; skipped
  kAborted,     // a stage failed; the pipeline is shutting down
  kNotTracked,  // decoded only as a reference for later frames (before the run's first tracked frame)
};

// Where a stage sends slots: on to the next stage, or out of the pipeline.
class Emitter {
 public:
  virtual void forward(FrameSlot& slot) = 0;
  virtual void release(FrameSlot& slot, ReleaseReason reason) = 0;

 protected:
  ~Emitter() = default;
};

// What a stage may ask the runner while it works.
class StageContext {
 public:
  // True once a stage failed or the run is being torn down: a stage waiting for something that
  // will never come (e.g. a depth hint from a failed backend) gives up and releases its slot.
  virtual bool aborting() const = 0;
  // How many slots a stage may keep between process() calls (the pool's size less one). A stage
  // holding every slot would leave the source none to bring the input it waits for (a decoder
  // holding pictures back until it gets more packets): it must give the oldest up first.
  virtual int maxHeldSlots() const = 0;
  // The core the pin map gives the named stage's helper thread ("<stage>.helper"), -1 for none.
  virtual int helperCore(std::string_view stage) const = 0;

 protected:
  ~StageContext() = default;
};

class Stage {
 public:
  virtual ~Stage() = default;
  // Short name used in reports and traces: "decode", "frontend", ...
  virtual std::string_view name() const = 0;
  // Whether the live policy may drop frames waiting in front of this stage (a decoder needs every
  // packet; a tracker can skip a frame).
  virtual bool canSkipInput() const { return false; }
  // Rough share of a frame's work, used to balance stages over a given number of threads.
  virtual int relativeCost() const { return 1; }
  // A stage that does part of a frame's work on a helper thread (StageHelper): whether it will, known
  // from construction (a pin map may then name "<stage>.helper"), and the helper once start() made it.
  // Such a stage runs its helper for every frame it forwards: the runner reads the helper's last run
  // then, for the trace and the profile.
  virtual bool usesHelper() const { return false; }
  virtual const StageHelper* helper() const { return nullptr; }
  virtual void start(const StageContext& /*context*/) {}
  // Handles one frame: calls out.forward() for each slot that goes on (zero or more, in order; a
  // stage may hold up to context.maxHeldSlots() slots and forward them later) or out.release().
  // When it throws, the stage has sent on or released every slot it held except `slot`, which the
  // runner releases unless the stage handed it on.
  virtual void process(FrameSlot& slot, Emitter& out) = 0;
  virtual void finish(Emitter& /*out*/) {}
};

// What a source stage made of a slot.
enum class Produced : std::uint8_t {
  kFrame,    // the next frame, to pass on
  kDamaged,  // a frame whose data could not be read (frame index and t_ns set): skipped, counted as damaged
  kEnd,      // the input ended, or the source was interrupted; the slot is unused
};

// The first stage: fills slots from an input.
class SourceStage {
 public:
  virtual ~SourceStage() = default;
  virtual std::string_view name() const = 0;
  virtual void start(const StageContext& /*context*/) {}
  // Fills the slot with the next frame (message, frame index, t_ns, arrival_ns).
  virtual Produced produce(FrameSlot& slot) = 0;
  // Makes a blocking produce() return kEnd soon; called from another thread.
  virtual void interrupt() {}
};

}  // namespace voca::pipeline
