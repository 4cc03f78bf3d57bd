#pragma once
// Recorded stereo datasets on disk: layout detection and frame lists (EuRoC/TUM-VI, KITTI odometry,
// VOCA video folders), and a writer for EuRoC folders.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "platform/filesystem/output_paths.h"
#include "voca/core/image.h"
#include "voca/trajectory/trajectory.h"

namespace voca {

enum class DatasetLayout { kEuroc, kKitti, kVocaVideo };

std::string_view layoutName(DatasetLayout layout);

// One stereo frame of an image dataset; the paths are empty for the video layout, whose frame i is
// the i-th frame of each video.
struct StereoFrameRef {
  int64_t t_ns = 0;
  std::filesystem::path left, right;
};

// What openDataset found: the frames in time order plus the files that go with them.
struct Dataset {
  DatasetLayout layout = DatasetLayout::kEuroc;
  std::filesystem::path root;  // the folder given (EuRoC: the one containing mav0, or mav0 itself)
  std::vector<StereoFrameRef> frames;
  std::filesystem::path video_left, video_right;  // kVocaVideo only
  std::optional<std::filesystem::path> ground_truth;
  // A file or folder for loadCalibration(): a Basalt JSON beside the dataset (a *.json whose name
  // contains "calib" in the dataset root), else the EuRoC mav0 folder (camN/sensor.yaml) or KITTI calib.txt.
  std::optional<std::filesystem::path> calibration;
  // Problems that did not stop reading (rows without images, unpaired timestamps), for the user.
  std::vector<std::string> warnings;
};

// Detects the layout of a dataset folder and lists its frames:
//  - EuRoC / TUM-VI: <root>/mav0/camN/data.csv (or <root> being mav0); stereo pairs by exact timestamp;
//    rows whose image is missing are skipped with a warning. Ground truth:
//    mav0/state_groundtruth_estimate0/data.csv if present.
//  - VOCA video: mav0/camN/data.mp4 with data.csv listing the frame timestamps in video order.
//  - KITTI odometry sequence: image_0/, image_1/, times.txt (seconds), calib.txt; ground truth
//    ../../poses/<sequence>.txt or poses.txt beside it if present.
// Throws InputError for a missing folder, an unknown layout (saying what was looked for) or a
// malformed csv/times line (file:line).
Dataset openDataset(const std::filesystem::path& path);

// What a command reads of this dataset, named for messages ("the dataset's mav0 folder"): the image or
// video folders (EuRoC and VOCA video: the whole mav0 folder; KITTI: image_0, image_1, times.txt,
// calib.txt) and its ground truth. No output of a command that reads the dataset may be one of them or
// lie in one (requireOutputsApart): `-o mav0/cam0/data.mp4` would truncate the video being decoded.
std::vector<NamedPath> datasetReadPaths(const Dataset& dataset);

// The ground truth of a run on this dataset: `file` when given, else the dataset's own (nullopt when
// it has none). A KITTI poses file carries no timestamps, so on a KITTI sequence it takes the
// sequence's times.txt; every other file is read by its detected format.
std::optional<Trajectory> loadGroundTruth(const Dataset& dataset,
                                          const std::optional<std::filesystem::path>& file = std::nullopt);

// Writes a standard EuRoC folder: <root>/mav0/camN/data/<t_ns>.png and camN/data.csv.
class EurocWriter {
 public:
  explicit EurocWriter(const std::filesystem::path& root, int num_cameras = 2);
  ~EurocWriter();
  EurocWriter(const EurocWriter&) = delete;
  EurocWriter& operator=(const EurocWriter&) = delete;

  // One image per camera, all with the same timestamp; timestamps must increase.
  void addFrame(int64_t t_ns, std::span<const GrayView> images);
  // Flushes and closes the csv files; throws if they could not be written. Called by the destructor
  // (which swallows errors) if not called before.
  void finish();

  const std::filesystem::path& mav0() const { return mav0_; }
  int64_t frameCount() const { return frame_count_; }

 private:
  std::filesystem::path mav0_;
  std::vector<std::ofstream> csv_;
  int64_t last_t_ns_ = 0;
  int64_t frame_count_ = 0;
  bool finished_ = false;
};

}  // namespace voca
