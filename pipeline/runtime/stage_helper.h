#pragma once
// A second thread for one stage: it runs a fixed task each time the stage asks, while the stage's
// own thread does other work of the same frame, and the stage waits for it before going on. The
// handoff is a pair of semaphores, so a request allocates nothing and an idle helper sleeps.

#include <exception>
#include <functional>
#include <semaphore>
#include <string>
#include <thread>

#include "pipeline/runtime/frame_slot.h"

namespace voca::pipeline {

class StageHelper {
 public:
  // Starts the thread (named `name`, as top -H and perf show it), which then waits for requests. A
  // thread inherits its creator's core affinity and scheduling class; core >= 0 pins it to that core
  // instead (a refusal is kept in pinWarning(), and the thread runs where it was created).
  StageHelper(std::string name, std::function<void()> task, int core = -1);
  // Stops and joins the thread; a request not yet waited for is finished first.
  ~StageHelper();
  StageHelper(const StageHelper&) = delete;
  StageHelper& operator=(const StageHelper&) = delete;

  // Runs the task once on the helper thread; everything the caller wrote before is visible to it.
  void request();
  // Returns when the requested run has finished, with everything it wrote visible to the caller;
  // rethrows what the task threw. Call once per request().
  void wait();

  // The last finished run: monotonic start and end, and the helper thread's CPU time over it.
  const StageTiming& lastRun() const { return last_run_; }
  // Why pinning to the requested core was refused; empty when it was not asked or succeeded.
  const std::string& pinWarning() const { return pin_warning_; }

 private:
  void loop();

  std::function<void()> task_;
  std::binary_semaphore go_{0};
  std::binary_semaphore done_{0};
  bool stop_ = false;  // written before a release of go_, read after its acquire
  bool pending_ = false;
  std::exception_ptr error_;
  StageTiming last_run_;     // written by the helper before a release of done_
  std::string pin_warning_;  // written by the helper before its first release of done_
  std::thread thread_;
};

}  // namespace voca::pipeline
