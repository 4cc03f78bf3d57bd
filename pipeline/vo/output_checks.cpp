#include "pipeline/vo/output_checks.h"

#include <array>
#include <vector>

#include "platform/filesystem/output_paths.h"

namespace voca::pipeline {

void requireOutputsApartFromInputs(const VoRunOptions& options, const Dataset* dataset,
                                   const std::optional<std::filesystem::path>& calibration,
                                   const std::optional<std::filesystem::path>& recording) {
  const std::array<NamedPath, 5> outputs = {NamedPath{"the trajectory file", options.trajectory_file},
                                            NamedPath{"the statistics file", options.statistics_file},
                                            NamedPath{"the trace file", options.pipeline_options.trace_path},
                                            NamedPath{"the overlay video", options.overlay_file},
                                            NamedPath{"the MCAP recording", options.mcap.file}};
  std::vector<NamedPath> inputs;
  if (dataset != nullptr) inputs = datasetReadPaths(*dataset);
  if (recording) inputs.push_back({"the recorded stream", *recording});
  if (options.ground_truth) inputs.push_back({"the ground truth", *options.ground_truth});
  if (calibration) inputs.push_back({"the calibration", *calibration});
  if (options.config && std::filesystem::exists(*options.config)) inputs.push_back({"the config", *options.config});
  requireOutputsApart(outputs, inputs);
  for (const NamedPath& output : outputs) requireWritableFile(output);
}

}  // namespace voca::pipeline
