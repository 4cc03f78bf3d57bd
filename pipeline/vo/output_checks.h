#pragma once
// The outputs of a run checked against its inputs before anything is written or read at length.

#include <filesystem>
#include <optional>

#include "formats/dataset/dataset.h"
#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

// Throws InputError naming both paths when an output of the run (trajectory, statistics, trace,
// overlay) is a file the run reads or lies in the dataset's data folders (`-o mav0/cam0/data.mp4`
// would truncate the video about to be decoded), or when two outputs are one file; and naming the
// path when an output cannot be written where it is (the statistics are written after the run: an
// unwritable path must not cost the whole run). dataset: nullptr for a stream or cameras; recording:
// the file a recorded stream is read from.
void requireOutputsApartFromInputs(const VoRunOptions& options, const Dataset* dataset,
                                   const std::optional<std::filesystem::path>& calibration,
                                   const std::optional<std::filesystem::path>& recording = std::nullopt);

}  // namespace voca::pipeline
