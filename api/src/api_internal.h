#pragma once
// What the API's sources share: the translation of the public options, poses and summaries to and
// from the pipeline's types, and of the library's internal exceptions into voca_rt::Error.

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <utility>
#include <vector>

#include "pipeline/sinks/sink_stage.h"
#include "pipeline/vo/vo_run.h"
#include "pipeline/vo/vo_session.h"
#include "voca/core/error.h"
#include "voca_rt/calibration.h"
#include "voca_rt/error.h"
#include "voca_rt/odometry.h"

namespace voca_rt::detail {

// Runs f, turning the library's exceptions into voca_rt::Error with the same message.
template <typename F>
auto translated(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const voca::InputError& e) {
    throw Error(Error::Kind::kInput, e.what());
  } catch (const voca::RuntimeFailure& e) {
    throw Error(Error::Kind::kRuntime, e.what());
  } catch (const std::filesystem::filesystem_error& e) {
    throw Error(Error::Kind::kInput, e.what());
  }
}

// The pipeline's options for the public ones (outputs, threads, decoder, mode, capacity). Throws
// InputError naming the option as the command line spells it.
voca::pipeline::VoRunOptions runOptions(const Options& options, bool realtime = false, double speed = 1.0);

// The calibration the options name: the value when it has cameras, else the file. Checked as a file
// is (two cameras, a baseline); throws InputError.
voca::StereoRig stereoRig(const Options& options);
voca::StereoRig stereoRig(const Calibration& calibration, const std::string& source);
Calibration calibration(const voca::StereoRig& rig);

// A finished frame as a public pose.
void toPose(const voca::pipeline::FrameSlot& slot, const voca::pipeline::StagePositions& positions, std::int64_t now_ns,
            Pose& pose);

// report: the run's summary, or the tracker's when the run estimated no poses.
Summary summary(const voca::pipeline::VoRunResult& result, bool estimate = true);

// The write stage's hand-over to the program: the callback, and a ring of the latest poses for
// poll() (full: the oldest unpolled gives way). consume() allocates nothing; poll() never waits
// longer than one pose's copy.
class PoseSink final : public voca::pipeline::FrameSink {
 public:
  PoseSink(PoseCallback callback, std::size_t poll_capacity);
  void begin(const voca::pipeline::StagePositions& positions) override { positions_ = positions; }
  void consume(const voca::pipeline::FrameSlot& slot) override;
  bool poll(Pose& pose);

 private:
  void lock();
  void unlock() { busy_.clear(std::memory_order_release); }

  PoseCallback callback_;
  voca::pipeline::StagePositions positions_;
  Pose current_;
  std::vector<Pose> ring_;
  std::size_t head_ = 0, size_ = 0;
  std::atomic_flag busy_ = ATOMIC_FLAG_INIT;
};

}  // namespace voca_rt::detail
