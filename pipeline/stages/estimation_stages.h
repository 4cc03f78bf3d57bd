#pragma once
// The algorithm stages: the KLT frontend and the sliding-window backend, and the channel that
// brings the backend's depth estimate back to the frontend a fixed number of frames later.

#include <cstdint>
#include <memory>

#include "pipeline/runtime/stage.h"
#include "pipeline/runtime/stage_helper.h"
#include "voca/backend/estimator.h"
#include "voca/calib/calibration.h"
#include "voca/frontend/frontend.h"

namespace voca::pipeline {

// The backend's mean landmark depth of frame k reaches the frontend for frame k + kLag (counted in
// frames both stages processed). A fixed lag keeps results independent of thread timing, and a lag
// of 2 lets the frontend track frame k while the backend estimates frame k - 1.
class DepthHintChannel {
 public:
  static constexpr int kLag = 2;
  DepthHintChannel();
  ~DepthHintChannel();
  // Backend side, once per frame in order.
  void push(double depth_m);
  // Frontend side, once per frame in order: the hint for the frontend's n-th frame (0 for the first
  // kLag frames). Waits for the backend; returns false when the context aborts first.
  bool pop(std::int64_t n, const StageContext& context, double& depth_m);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class FrontendStage final : public Stage {
 public:
  // hints: non-null when the config's stereo guess uses the backend's depth. camera_threads 2: a
  // helper thread runs half of each frame's work items (KltFrontend::runItem) while the stage's
  // thread runs the other half (the same results).
  FrontendStage(const FrontendConfig& config, const StereoRig& rig, const FrontendCapacities& capacities,
                DepthHintChannel* hints, bool keep_left_traces, int camera_threads = 1);
  std::string_view name() const override { return "frontend"; }
  bool canSkipInput() const override { return true; }
  int relativeCost() const override { return 4; }
  // Starts the helper thread, if any, from the stage's thread: it shares its scheduling class, and its
  // core unless the pin map names "frontend.helper".
  void start(const StageContext& context) override;
  bool usesHelper() const override { return camera_threads_ == 2; }
  const StageHelper* helper() const override { return helper_.get(); }
  void process(FrameSlot& slot, Emitter& out) override;

 private:
  KltFrontend frontend_;
  int camera_threads_;
  std::unique_ptr<StageHelper> helper_;
  // The frame whose work items the helper runs, and how many it has, set before each request.
  const DecodedStereoFrame* helper_frame_ = nullptr;
  int frame_items_ = 0;
  DepthHintChannel* hints_;
  bool keep_left_traces_;
  const StageContext* context_ = nullptr;
  std::int64_t frames_ = 0;
  std::int64_t last_index_ = -1;
};

class BackendStage final : public Stage {
 public:
  // copy_landmarks: fill FrameSlot::landmarks_world (slots reserved for landmarkCapacity()) for a
  // sink that reads them.
  BackendStage(const BackendConfig& config, const StereoRig& rig, DepthHintChannel* hints, bool copy_landmarks = false);
  std::string_view name() const override { return "backend"; }
  int relativeCost() const override { return 4; }
  void process(FrameSlot& slot, Emitter& out) override;
  int landmarkCapacity() const { return estimator_.landmarkCapacity(); }

 private:
  VoEstimator estimator_;
  DepthHintChannel* hints_;
  bool copy_landmarks_;
};

}  // namespace voca::pipeline
