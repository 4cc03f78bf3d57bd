#include "pipeline/stages/estimation_stages.h"

#include <readerwriterqueue/readerwritercircularbuffer.h>

#include <algorithm>

#include <fmt/format.h>

#include "voca/core/error.h"

namespace voca::pipeline {

struct DepthHintChannel::Impl {
  // The backend is at most a pool's worth of frames behind the frontend; 64 leaves room for any pool.
  moodycamel::BlockingReaderWriterCircularBuffer<double> queue{64};
};

DepthHintChannel::DepthHintChannel() : impl_(std::make_unique<Impl>()) {}
DepthHintChannel::~DepthHintChannel() = default;

void DepthHintChannel::push(double depth_m) { impl_->queue.wait_enqueue(depth_m); }

bool DepthHintChannel::pop(std::int64_t n, const StageContext& context, double& depth_m) {
  depth_m = 0.0;
  if (n < kLag) return true;
  while (!impl_->queue.wait_dequeue_timed(depth_m, 20000)) {
    if (context.aborting()) return false;
  }
  return true;
}

FrontendStage::FrontendStage(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities,
                             DepthHintChannel* hints, bool keep_left_traces, int camera_threads)
    : frontend_(config, rig, capacities),
      camera_threads_(camera_threads),
      hints_(hints),
      keep_left_traces_(keep_left_traces) {
  if (camera_threads != 1 && camera_threads != 2) {
    throw InputError(fmt::format("frontend: {} camera threads; 1 or 2", camera_threads));
  }
}

void FrontendStage::start(const StageContext& context) {
  context_ = &context;
  if (camera_threads_ == 2 && helper_ == nullptr) {
    helper_ = std::make_unique<StageHelper>(
        "voca-frontend.helper",
        [this] {
          for (int item = 1; item < frame_items_; item += 2) frontend_.runItem(item, *helper_frame_);
        },
        context.helperCore(name()));
  }
}

void FrontendStage::process(FrameSlot& slot, Emitter& out) {
  DecodedStereoFrame& frame = slot.frame;
  // Frames of the source this stage never saw (dropped or damaged), so the tracker and the backend
  // know the motion since the last frame spans more than one interval.
  frame.frames_missing_before =
      last_index_ < 0 ? 0 : static_cast<int>(std::max<std::int64_t>(0, frame.frame_index - last_index_ - 1));
  last_index_ = frame.frame_index;
  if (hints_ != nullptr && !hints_->pop(frames_, *context_, frame.depth_hint_m)) {
    out.release(slot, ReleaseReason::kAborted);
    return;
  }
  ++frames_;
  const int items = frontend_.beginFrame(frame, slot.frontend_stats);
  if (helper_ == nullptr) {
    for (int item = 0; item < items; ++item) frontend_.runItem(item, frame);
  } else {
    // The helper runs the odd items, this thread the even ones: the frontend makes its items of about
    // equal work.
    helper_frame_ = &frame;
    frame_items_ = items;
    helper_->request();
    try {
      for (int item = 0; item < items; item += 2) frontend_.runItem(item, frame);
    } catch (...) {
      helper_->wait();  // the helper works on the same frontend: it must finish first
      throw;
    }
    helper_->wait();
  }
  frontend_.endFrame(frame, slot.tracked, slot.frontend_stats);
  if (keep_left_traces_) {
    const auto traces = frontend_.traces(0);
    slot.left_traces.assign(traces.begin(), traces.end());
  }
  out.forward(slot);
}

BackendStage::BackendStage(const BackendConfig& config, const StereoRig& rig, DepthHintChannel* hints,
                           bool copy_landmarks)
    : estimator_(config, rig), hints_(hints), copy_landmarks_(copy_landmarks) {}

void BackendStage::process(FrameSlot& slot, Emitter& out) {
  slot.pose = estimator_.process(slot.tracked);
  if (hints_ != nullptr) hints_->push(slot.pose.mean_depth_m);
  if (copy_landmarks_) {
    // Within the slot's reserved capacity: resizing never reallocates.
    std::vector<Eigen::Vector3f>& points = slot.landmarks_world;
    points.resize(points.capacity());
    points.resize(estimator_.worldLandmarks(points));
  }
  out.forward(slot);
}

}  // namespace voca::pipeline
