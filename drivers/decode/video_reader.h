#pragma once
// Video files -> DecodedFrames with dataset timestamps: one camera (VideoReader) or the two cameras
// of a VOCA video dataset in lockstep (StereoVideoReader).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "drivers/decode/video_decoder.h"
#include "formats/dataset/dataset.h"

namespace voca::decode {

// Demuxes and decodes one video on the calling thread. Frame i gets timestamp t_ns[i] (frames follow
// data.csv order); with no timestamps the pts converted to ns is used. Throws voca::InputError when
// the video and the timestamps disagree in frame count (up front from the container index, or when
// either runs out first), when a frame is lost (pts out of step in a constant-rate stream) and for
// corrupt data, naming the file and the frame index.
class VideoReader {
 public:
  VideoReader(const std::filesystem::path& video, std::vector<std::int64_t> t_ns, const DecoderOptions& options = {},
              const DecoderProbe* probe = nullptr);
  ~VideoReader();
  VideoReader(const VideoReader&) = delete;
  VideoReader& operator=(const VideoReader&) = delete;

  // The next frame, false after the last one.
  bool next(DecodedFrame& frame);

  const StreamInfo& stream() const;
  const std::filesystem::path& path() const;
  const std::string& decoderDescription() const;
  // Number of frames when known (timestamps given or container index), else 0.
  std::int64_t expectedFrames() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The two cameras of a VOCA video dataset (mav0/camN/data.mp4 + data.csv), frame by frame.
class StereoVideoReader {
 public:
  // dataset must have layout kVocaVideo. Checks that both videos have as many frames as the
  // dataset lists (InputError naming the camera otherwise, with the dataset's csv warnings).
  StereoVideoReader(const Dataset& dataset, const DecoderOptions& options = {}, const DecoderProbe* probe = nullptr);
  // Explicit files and timestamps (both videos must have t_ns.size() frames).
  StereoVideoReader(const std::filesystem::path& left, const std::filesystem::path& right,
                    const std::vector<std::int64_t>& t_ns, const DecoderOptions& options = {},
                    const DecoderProbe* probe = nullptr, const std::string& context = {});

  // Both cameras' next frame (same index and timestamp); false after the last stereo frame.
  bool next(DecodedFrame& left, DecodedFrame& right);
  std::size_t size() const { return num_frames_; }
  VideoReader& camera(int index) { return index == 0 ? *left_ : *right_; }

 private:
  std::unique_ptr<VideoReader> left_, right_;
  std::size_t num_frames_ = 0;
};

// Timestamps of a VOCA video dataset.
std::vector<std::int64_t> datasetTimestamps(const Dataset& dataset);

}  // namespace voca::decode
