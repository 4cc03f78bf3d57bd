#include "pipeline/runtime/stage_helper.h"

#include <utility>

#include "platform/realtime/thread_control.h"

namespace voca::pipeline {

StageHelper::StageHelper(std::string name, std::function<void()> task) : task_(std::move(task)) {
  thread_ = std::thread([this, name = std::move(name)] {
    platform::nameCurrentThread(name);
    loop();
  });
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
    try {
      task_();
    } catch (...) {
      error_ = std::current_exception();
    }
    done_.release();
  }
}

}  // namespace voca::pipeline
