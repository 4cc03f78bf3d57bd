#pragma once
// `voca mv`: draws what the codec saw in a video: each frame with its block partitions, the motion
// vectors as arrows (forward flow) and the vectors that median thresholding flags as likely outliers
// (the VOCA paper's Fig. 3), written as one PNG per frame or as one .mp4.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>

#include "voca/motion/motion_field.h"

namespace voca::pipeline {

struct MotionPlotOptions {
  std::filesystem::path input;  // a video file, or a VOCA video folder (mav0/camN/data.mp4)
  std::filesystem::path out;    // the output folder (created)
  int camera = 0;               // which camera of a folder: 0 or 1
  // Frames [first_frame, end_frame) are drawn; the earlier ones are decoded all the same, since
  // later P-frames refer to them.
  std::int64_t first_frame = 0;
  std::int64_t end_frame = std::numeric_limits<std::int64_t>::max();
  std::string format = "png";  // png (mv_<frame>.png) or mp4 (mv.mp4)
  std::string decoder = "auto";
  float arrow_scale = 1.0f;  // arrow lengths multiplied by this for visibility
  OutlierParams outliers;
  bool strict = false;   // stop at the first damaged picture instead of drawing its concealment
  bool progress = true;  // the progress line and warnings on stderr
  // Asked before each frame; true ends the drawing there, with the .mp4 closed so that it plays.
  std::function<bool()> stop_requested;
};

struct MotionPlotResult {
  std::filesystem::path video;    // the video drawn (of a folder: the camera's data.mp4)
  std::filesystem::path written;  // the output folder, or the .mp4
  int frames = 0;                 // frames drawn: 0 when none of the video is in the range
  int damaged = 0;                // of which damaged (drawn as the decoder concealed them)
  std::int64_t vectors = 0;
  std::int64_t outliers = 0;  // vectors flagged as likely outliers
  bool stopped = false;       // stop_requested() ended the drawing early
};

// Validates the options (InputError naming the option), keeps the output apart from the input,
// decodes the video and draws every frame of the range.
MotionPlotResult plotMotionVectors(const MotionPlotOptions& options);

}  // namespace voca::pipeline
