#pragma once
// Recorded datasets as stereo sources: image folders (EuRoC, TUM-VI, KITTI) deliver raw frames
// read one at a time (long sequences need no memory for all images); VOCA video folders
// (mav0/camN/data.mp4 + data.csv) deliver each camera's compressed packets with the dataset's
// timestamps, for the pipeline's decode stage.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "drivers/decode/demuxer.h"
#include "drivers/source/stereo_source.h"
#include "formats/dataset/dataset.h"

namespace voca {

// How a recorded dataset is replayed.
struct ReplayOptions {
  // Track frames [first_frame, first_frame + max_frames) of the dataset (max_frames 0 = to the end).
  // A later start is how the evaluation harness repeats a run with a different history.
  int first_frame = 0;
  int max_frames = 0;
  // A video that ends before its data.csv does: true throws InputError (naming the camera and the
  // frame); false ends the replay there and reports it in warnings(). An image that cannot be read
  // (corrupt or vanished PNG): true throws InputError naming the file and the frame; false delivers
  // the frame marked damaged (the pipeline skips and counts it) and names the file in warnings().
  bool strict = true;
};

// EuRoC / TUM-VI / KITTI image folders: frame i is the i-th stereo pair of the dataset.
class ImageDatasetSource : public StereoSource {
 public:
  // dataset must not be a video folder. Reads the first pair to learn the image size (InputError
  // when it cannot be read or the two cameras differ in size); non-strict replay learns it from the
  // first pair that can be read.
  ImageDatasetSource(Dataset dataset, const ReplayOptions& options = {});

  const SourceInfo& info() const override { return info_; }
  bool next(RawStereoFrame& frame) override;
  void interrupt() override { interrupted_ = true; }

  // Frames skipped as damaged in non-strict replay, each naming its unreadable file (the first
  // few; then how many more).
  std::vector<std::string> warnings() const override;

 private:
  Dataset dataset_;
  bool strict_ = true;
  SourceInfo info_;
  std::size_t count_ = 0;
  std::size_t index_ = 0;
  std::atomic<bool> interrupted_{false};
  std::vector<std::string> damaged_;  // the first kListedDamaged messages
  std::int64_t unlisted_damaged_ = 0;
};

// A VOCA video folder: both cameras' packets in lockstep, frame i stamped with data.csv's row i.
class VideoFolderSource : public StereoSource {
 public:
  // dataset must be a video folder. Throws InputError when a video cannot be opened or its
  // container index disagrees with data.csv in frame count.
  VideoFolderSource(Dataset dataset, const ReplayOptions& options = {});
  ~VideoFolderSource() override;

  const SourceInfo& info() const override { return info_; }
  bool next(EncodedStereoPacket& packet) override;
  void interrupt() override { interrupted_ = true; }

  // Problems that ended the replay early in non-strict mode (a truncated video).
  std::vector<std::string> warnings() const override { return warnings_; }

 private:
  Dataset dataset_;
  ReplayOptions options_;
  SourceInfo info_;
  std::array<std::unique_ptr<decode::Demuxer>, 2> demuxers_;
  std::size_t count_ = 0;
  std::size_t index_ = 0;
  std::atomic<bool> interrupted_{false};
  bool ended_ = false;
  std::vector<std::string> warnings_;
};

// The source for a dataset folder as openDataset() found it: video folders deliver packets, image
// folders raw frames.
std::unique_ptr<StereoSource> openDatasetSource(const Dataset& dataset, const ReplayOptions& options = {});

}  // namespace voca
