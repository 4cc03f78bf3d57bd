#pragma once
// A second thread for one stage: it runs a fixed task each time the stage asks, while the stage's
// own thread does other work of the same frame, and the stage waits for it before going on. The
// handoff is a pair of semaphores, so a request allocates nothing and an idle helper sleeps.

#include <exception>
#include <functional>
#include <semaphore>
#include <string>
#include <thread>

namespace voca::pipeline {

class StageHelper {
 public:
  // Starts the thread (named `name`, as top -H and perf show it), which then waits for requests. A
  // thread inherits its creator's core affinity and scheduling class.
  StageHelper(std::string name, std::function<void()> task);
  // Stops and joins the thread; a request not yet waited for is finished first.
  ~StageHelper();
  StageHelper(const StageHelper&) = delete;
  StageHelper& operator=(const StageHelper&) = delete;

  // Runs the task once on the helper thread; everything the caller wrote before is visible to it.
  void request();
  // Returns when the requested run has finished, with everything it wrote visible to the caller;
  // rethrows what the task threw. Call once per request().
  void wait();

 private:
  void loop();

  std::function<void()> task_;
  std::binary_semaphore go_{0};
  std::binary_semaphore done_{0};
  bool stop_ = false;  // written before a release of go_, read after its acquire
  bool pending_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace voca::pipeline
