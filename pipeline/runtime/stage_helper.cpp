#include "pipeline/runtime/stage_helper.h"

#include <utility>

#include "platform/realtime/clock.h"
#include "platform/realtime/thread_control.h"

namespace voca::pipeline {

StageHelper::StageHelper(std::string name, std::function<void()> task, int core) : task_(std::move(task)) {
  thread_ = std::thread([this, name = std::move(name), core] {
    platform::nameCurrentThread(name);
    if (core >= 0) {
      const platform::ControlResult pinned = platform::pinCurrentThread(core);
      if (!pinned.ok) pin_warning_ = pinned.message;
    }
    done_.release();  // started: the pin's outcome is known
    loop();
  });
  done_.acquire();
}

StageHelper::~StageHelper() {
  if (pending_) done_.acquire();
  stop_ = true;
  go_.release();
  thread_.join();
}

void StageHelper::request() {
  pending_ = true;
  go_.release();
}

void StageHelper::wait() {
  done_.acquire();
  pending_ = false;
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void StageHelper::loop() {
  for (;;) {
    go_.acquire();
    if (stop_) return;
    StageTiming run;
    run.start_ns = platform::monotonicNs();
    run.cpu_start_ns = platform::threadCpuNs();
    try {
      task_();
    } catch (...) {
      error_ = std::current_exception();
    }
    run.cpu_ns = platform::threadCpuNs() - run.cpu_start_ns;
    run.end_ns = platform::monotonicNs();
    last_run_ = run;
    done_.release();
  }
}

}  // namespace voca::pipeline
