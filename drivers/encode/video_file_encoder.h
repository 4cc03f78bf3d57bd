#pragma once
// A whole sequence of gray frames into an .mp4 (datasets -> video, two-pass constant bitrate as the
// VOCA paper encodes).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "voca/core/image.h"

namespace voca::encode {

// Called for each frame given to encodeVideoFile: pass (1-based), number of passes, frame index.
using EncodeProgress = std::function<void(int pass, int num_passes, int frame_index)>;
// Supplies the whole sequence, in order, by calling emit once per frame. It is called once per
// pass, so it must produce the same frames each time.
using FrameSource = std::function<void(const std::function<void(GrayView)>& emit)>;

// What encodeVideoFile produced.
struct EncodeResult {
  int num_frames = 0;
  int width = 0, height = 0;  // coded size
  int num_keyframes = 0;
  std::int64_t payload_bytes = 0;         // sum of the video packets
  std::int64_t file_bytes = 0;            // the .mp4, container included
  double duration_s = 0.0;                // num_frames / fps
  double achieved_bitrate_bps = 0.0;      // payload_bytes * 8 / duration_s
  std::vector<double> pass_ms_per_frame;  // encode wall time per frame, one entry per pass
};

// Encodes all frames of source into an .mp4 at path (created or overwritten), with pts = frame
// index at settings' frame rate. Two passes when settings.two_pass (statistics in a temporary
// folder that is removed afterwards). Throws InputError on an empty source, frames of different
// sizes or an unwritable path; RuntimeFailure when libav fails.
EncodeResult encodeVideoFile(const std::filesystem::path& path, const EncoderSettings& settings,
                             const FrameSource& source, const EncodeProgress& progress = {});

}  // namespace voca::encode
