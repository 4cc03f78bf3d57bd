#pragma once
// Reads the stereo access units of a VOCA video folder (mav0/camN/data.mp4 + data.csv, what `voca
// encode` and `voca record` write) as an encoder on a robot would hand them over: Annex B byte
// streams with the parameter sets in band, stamped with the dataset's sensor times. For feeding
// Odometry::pushH264 from a recording.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "voca_rt/export.h"

namespace voca_rt {

struct StereoPacket {
  std::int64_t t_ns = 0;
  std::int64_t frame_index = 0;
  std::vector<std::uint8_t> left, right;  // reused between reads
};

class VOCA_RT_API VideoFolderReader {
 public:
  // Opens both cameras' videos (a dataset folder or its mav0 folder). Throws Error naming what is
  // missing or unreadable.
  explicit VideoFolderReader(const std::string& folder);
  ~VideoFolderReader();
  VideoFolderReader(const VideoFolderReader&) = delete;
  VideoFolderReader& operator=(const VideoFolderReader&) = delete;

  // The next frame's access units; false at the end.
  bool next(StereoPacket& packet);

  int width() const;
  int height() const;
  std::int64_t frames() const;  // in data.csv
  // The calibration written beside the videos (calib.json), empty when there is none.
  std::string calibrationFile() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca_rt
