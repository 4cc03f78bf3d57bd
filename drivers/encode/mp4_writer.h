#pragma once
// An encoder's packets into an .mp4 file (libavformat).

#include <filesystem>
#include <memory>

#include "drivers/encode/video_encoder.h"

namespace voca::encode {

// Writes one encoder's packets into an .mp4 file as they come (live recording). The file is complete
// and playable after end().
class Mp4Writer {
 public:
  // Opens the file, so an unwritable path fails before any encoding (InputError).
  explicit Mp4Writer(const std::filesystem::path& path);
  ~Mp4Writer();
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  // Takes the stream parameters (size, rate, codec headers) from an open encoder opened with
  // global_header = true, and writes the file header.
  void begin(const VideoEncoder& encoder);
  void write(const EncodedPacket& packet);
  // Writes the index (moov) and closes the file; idempotent. Throws RuntimeFailure on write errors.
  void end();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::encode
