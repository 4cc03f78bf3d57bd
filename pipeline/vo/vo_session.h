#pragma once
// One run of the visual odometry on an open source: the staged pipeline read -> [encode] -> [decode]
// -> frontend -> [backend] -> write and its sinks (trajectory file, statistics, overlay video,
// progress, the caller's), built at construction with every buffer it will need, then run once.
// runVisualOdometryOn runs a session on the caller's thread; the library API runs one on a thread
// of its own while its caller pushes frames into the source.

#include <memory>
#include <optional>
#include <string>

#include "drivers/source/stereo_source.h"
#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

class VoSession {
 public:
  // Throws InputError for an input the run cannot use: images that do not match the calibration, a
  // thread layout or pin map that does not fit the stages, an output that cannot be opened. The
  // source and options.extra_sinks must outlive the session.
  VoSession(StereoSource& source, const StereoRig& rig, const VocaConfig& config, const VoRunOptions& options,
            std::optional<Trajectory> ground_truth = {}, std::string ground_truth_name = {});
  ~VoSession();
  VoSession(const VoSession&) = delete;
  VoSession& operator=(const VoSession&) = delete;

  // Runs until the source ends, a stop is requested or a stage fails, on the calling thread and the
  // pipeline's own. A stage failing does not throw: the result carries it. Call once.
  void run();
  // Makes a running session stop as a stop request does (the source is interrupted, the queues
  // drain, everything estimated is kept). Any thread, any time.
  void requestStop();
  // True once a stage failed (from any thread, while the session runs).
  bool failed() const;

  const StagePositions& positions() const;
  // The configuration as the run uses it (after the options' overrides).
  const VocaConfig& config() const;
  // "decoder: software", or the hardware choice; empty for raw images.
  const std::string& decoderDescription() const;
  // After run(): trajectory, statistics, latency, drops and the evaluation against the ground truth.
  VoRunResult takeResult();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The options' overrides of a configuration (prior mode, I-frame bridging).
VocaConfig configForRun(const VocaConfig& config, const VoRunOptions& options);

}  // namespace voca::pipeline
