#pragma once
// Input selection for a run: what `voca run <input>` names (a raw dataset, optionally encoded first
// the way the paper did; a VOCA video folder; a stream URL; a recording of a stream) opened as a
// source of stereo frames, with the calibration, config and ground truth that go with it.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/source/stereo_source.h"
#include "pipeline/vo/vo_run.h"
#include "platform/filesystem/temp_dir.h"

namespace voca {
class NetworkStereoSource;
}

namespace voca::pipeline {

struct RunInput {
  std::unique_ptr<StereoSource> source;
  StereoRig rig;
  RunConfig config;  // as resolved for the input; VoRunOptions' mode and bridging are applied by the run
  std::optional<Trajectory> ground_truth;
  std::string ground_truth_name;
  // A raw dataset encoded for this run (VoRunOptions::encode_bitrate_bps): the temporary folder,
  // removed with the input, and the input's description ("seq encoded at 500 kbit/s").
  std::unique_ptr<TempDir> encoding;
  std::string encoding_description;
  NetworkStereoSource* stream = nullptr;  // the source when it is a stream: it says why it ended
  std::vector<std::string> warnings;      // the dataset's, and options that do nothing for this input
  // Set when the run ended before its first frame (a stop request while encoding or while waiting
  // for the stream): the result to report; `source` is null.
  std::optional<VoRunResult> stopped;
};

// Opens options.input after checking the options that can be checked before any work (capacity,
// outputs apart from inputs and writable). Throws InputError for bad input: a missing dataset,
// calibration or config, a file that is no recording, a stream without --calib.
RunInput openRunInput(const VoRunOptions& options);

// The end of a run on an opened input: the input's description, warnings and end reason added to
// the run's result.
void addInputToResult(RunInput& input, VoRunResult& result);

}  // namespace voca::pipeline
