#include "pipeline/vo/vo_runner.h"

#include "formats/config/config.h"
#include "pipeline/vo/run_input.h"
#include "pipeline/vo/vo_session.h"
#include "platform/realtime/stop_signal.h"

namespace voca::pipeline {

RunConfig resolveRunConfig(const std::optional<std::filesystem::path>& config, bool kitti_input) {
  if (config) return {loadConfig(*config), config->string()};
  // KITTI's street scenes and 0.54 m baseline put the paper's 2 m stereo guess ~190 px off.
  const std::string name = kitti_input ? "kitti" : "euroc";
  return {builtinConfig(name), name + " (built in)"};
}

std::function<bool()> stopRequest(const VoRunOptions& options) {
  return options.pipeline_options.stop_requested ? options.pipeline_options.stop_requested
                                                 : std::function<bool()>(platform::stopRequested);
}

VoRunResult runVisualOdometry(const VoRunOptions& options) {
  RunInput input = openRunInput(options);
  VoRunResult result;
  if (input.stopped) {
    result = std::move(*input.stopped);
    result.config = configForRun(result.config, options);
  } else {
    result = runVisualOdometryOn(*input.source, input.rig, input.config.config, options, input.ground_truth,
                                 input.ground_truth_name);
  }
  addInputToResult(input, result);
  if (!options.statistics_file.empty()) writeStatisticsJson(result, options.statistics_file);
  return result;
}

VoRunResult runVisualOdometryOn(StereoSource& source, const StereoRig& rig, const VocaConfig& config,
                                const VoRunOptions& options, const std::optional<Trajectory>& ground_truth,
                                const std::string& ground_truth_name) {
  VoSession session(source, rig, config, options, ground_truth, ground_truth_name);
  session.run();
  return session.takeResult();
}

}  // namespace voca::pipeline
