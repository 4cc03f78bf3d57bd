#pragma once
// Datasets -> the VOCA video layout: one .mp4 per camera with the original timestamps in data.csv,
// ground truth and calibration beside them (what `voca encode` does).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "formats/dataset/dataset.h"

namespace voca::platform {
class ProgressLine;
}

namespace voca::encode {

// What to encode and how.
struct DatasetEncodeOptions {
  EncoderSettings settings;                          // its frame rate is used unless use_dataset_fps
  bool use_dataset_fps = false;                      // encode at the dataset's own rate (median frame interval)
  std::vector<int> cameras = {0, 1};                 // 0 = left, 1 = right
  std::optional<std::filesystem::path> calibration;  // overrides the one found with the dataset
  // Polled once per encoded frame; true ends the encoding as a failure would (what it wrote is
  // removed, the previous output stays) and encodeDataset returns with `stopped` set.
  std::function<bool()> stop_requested;
};

// One encoded camera.
struct CameraEncodeReport {
  int camera = 0;
  std::filesystem::path video;
  std::int64_t input_bytes = 0;  // the camera's PNG files, or its input video
  EncodeResult result;
};

// What encodeDataset did.
struct DatasetEncodeReport {
  DatasetLayout input_layout = DatasetLayout::kEuroc;
  int num_frames = 0;
  int fps_num = 0, fps_den = 1;  // the rate the videos were encoded at
  // The dataset's own rate (datasetFrameRate; the encoding rate for a single frame). The paper encodes
  // at 30 fps whatever the dataset's rate, so a stream's bitrate over the dataset's real time is the
  // achieved one times realTimeRateScale().
  int dataset_fps_num = 0, dataset_fps_den = 1;
  bool timedAtDatasetRate() const { return dataset_fps_num * fps_den == fps_num * dataset_fps_den; }
  double realTimeRateScale() const {
    return (static_cast<double>(dataset_fps_num) * fps_den) / (static_cast<double>(dataset_fps_den) * fps_num);
  }
  std::vector<CameraEncodeReport> cameras;
  std::int64_t input_bytes = 0;   // all encoded cameras
  std::int64_t output_bytes = 0;  // all videos
  std::int64_t raw_bytes = 0;     // frames x width x height of the input: uncompressed 8-bit size
  std::optional<std::filesystem::path> calibration_written;
  std::optional<std::filesystem::path> ground_truth_written;
  std::vector<std::string> warnings;
  bool stopped = false;  // options.stop_requested ended the encoding: nothing was written
};

// Called per frame: camera, pass (1-based), number of passes, frame index, number of frames.
using DatasetEncodeProgress = std::function<void(int camera, int pass, int num_passes, int frame, int num_frames)>;
// Called with each warning as it is found (the dataset's own before the encoding starts); the report
// lists them all too.
using DatasetEncodeWarning = std::function<void(const std::string& warning)>;

// The dataset's frame rate as a rational, from the median frame interval: a whole rate when within
// 0.05 % of one (EuRoC's 20 Hz), an NTSC rate N*1000/1001 likewise, else millihertz precision.
void datasetFrameRate(const Dataset& dataset, int& fps_num, int& fps_den);

// Encodes a raw EuRoC / TUM-VI / KITTI dataset, or re-encodes a VOCA video folder, into
// <out>/mav0/camN/data.mp4 + data.csv (`#timestamp [ns],filename`, filename <t_ns>.png as the
// official VOCA layout has it). Ground truth is copied to mav0/state_groundtruth_estimate0/data.csv
// (KITTI poses converted to EuRoC csv with times.txt); the calibration, if the dataset or
// options.calibration provides one, is written as Basalt JSON to <out>/calib.json with the coded
// image size. Throws InputError for an unknown or missing dataset, bad options, an output folder
// that cannot be written or that is the input itself, and an image that cannot be read (naming it:
// the video must not silently lack a frame). A failed encoding removes what it created: the output
// folder if it did not exist, else the folders and files it added. Every file is written under a
// temporary name beside its final one (`data.partial.mp4`) and renamed into place only when the
// whole encoding succeeded, so a failed or stopped re-encoding leaves the previous output intact.
DatasetEncodeReport encodeDataset(const std::filesystem::path& input, const std::filesystem::path& out,
                                  const DatasetEncodeOptions& options, const DatasetEncodeProgress& progress = {},
                                  const DatasetEncodeWarning& warn = {});

// The progress of encodeDataset on a progress line: "cam0 pass 1/2: frame 120/800 (15%)", updated
// at each whole percent and ended after each camera's last pass.
DatasetEncodeProgress progressOnLine(platform::ProgressLine& line);

// Encodes a raw dataset the way the paper did (two-pass libx264 at bitrate_bps with its x264 options)
// into a VOCA video folder at out, for a run that replays it: `voca run --encode`, the benches and
// the evaluation harness. Progress goes to stderr when asked. Returns false, having written nothing,
// when stop_requested() turns true first; throws as encodeDataset does.
// keyframe_interval > 0 replaces the paper's keyint of 1000 (a stream that must recover from damage
// soon).
bool encodeForReplay(const std::filesystem::path& input, const std::filesystem::path& out, std::int64_t bitrate_bps,
                     const std::optional<std::filesystem::path>& calibration, bool progress,
                     const std::function<bool()>& stop_requested, int keyframe_interval = 0);

}  // namespace voca::encode
