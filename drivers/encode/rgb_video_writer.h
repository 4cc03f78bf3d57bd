#pragma once
// RGB pictures -> an .mp4 file (H.264, or MPEG-4 Part 2 when libx264 is absent), for visualisations
// such as `voca mv --format mp4`. Not for datasets: use drivers/encode for those.

#include <filesystem>
#include <memory>

#include "voca/core/image.h"

namespace voca::encode {

class RgbVideoWriter {
 public:
  // Frames must all have the size of the first one. fps as a rational. Opens the file (InputError when it
  // cannot be written).
  RgbVideoWriter(const std::filesystem::path& path, int fps_num = 30, int fps_den = 1);
  ~RgbVideoWriter();  // finishes the file if finish() was not called (errors are swallowed there)
  RgbVideoWriter(const RgbVideoWriter&) = delete;
  RgbVideoWriter& operator=(const RgbVideoWriter&) = delete;

  // Throws InputError when the file cannot be written or the frame size changes.
  void write(RgbView frame);
  // Flushes the encoder and writes the container index.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::encode
