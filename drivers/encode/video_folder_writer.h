#pragma once
// Live stereo frames -> a VOCA video folder (`voca record`): mav0/cam0/data.mp4 and mav0/cam1/data.mp4
// encoded as the frames arrive, data.csv with each frame's capture timestamp, and the calibration
// as calib.json, so `voca run` replays the recording later. The folder is complete after finish(),
// which a stopped recording also reaches.

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "drivers/encode/live_encoder.h"
#include "drivers/encode/mp4_writer.h"
#include "drivers/source/stereo_source.h"

namespace voca::encode {

class VideoFolderWriter {
 public:
  // Creates out (which must not hold a recording already) and opens both encoders for frames of
  // width x height, as the live encoder chooses (encoder.kind auto: the first that opens; the second
  // camera gets the first's kind). calibration, when given, is loaded (any format loadCalibration reads), checked
  // against the frame size and written as out/calib.json. Throws InputError for an unwritable or
  // non-empty folder, a calibration that does not match, or bad settings.
  VideoFolderWriter(const std::filesystem::path& out, int width, int height, const LiveEncoderSettings& encoder,
                    const std::optional<std::filesystem::path>& calibration = {});
  ~VideoFolderWriter();  // finishes the files if finish() was not called (errors are swallowed there)
  VideoFolderWriter(const VideoFolderWriter&) = delete;
  VideoFolderWriter& operator=(const VideoFolderWriter&) = delete;

  // Encodes and writes one stereo frame; its t_ns goes into both data.csv files.
  void write(const RawStereoFrame& frame);
  // Drains the encoders and writes the mp4 indexes; the folder is then playable.
  void finish();

  std::int64_t frames() const { return frames_; }
  std::int64_t videoBytes() const { return video_bytes_; }  // compressed payload so far, both cameras
  const std::filesystem::path& folder() const { return out_; }
  // The encoder chosen, one line ("encoder: x264 (libx264, 1000 kbit/s, GOP 120)").
  const std::string& encoderDescription() const { return encoder_description_; }

 private:
  void writePackets(std::size_t camera, std::span<const EncodedPacket> packets);

  std::filesystem::path out_;
  std::string encoder_description_;
  std::array<VideoEncoder, 2> encoders_;
  std::array<std::unique_ptr<Mp4Writer>, 2> writers_;
  std::array<std::ofstream, 2> csv_;
  std::int64_t frames_ = 0;
  std::int64_t video_bytes_ = 0;
  bool finished_ = false;
};

// What a recording did.
struct RecordReport {
  std::int64_t frames = 0;
  std::int64_t first_t_ns = 0, last_t_ns = 0;
  std::int64_t video_bytes = 0;
  std::int64_t raw_bytes = 0;  // frames x 2 x width x height: the 8-bit gray size it replaces
  SourceCounters source;       // frames the cameras lost or could not pair
  bool stopped = false;        // stop_requested ended it (not the source)
  std::string error;           // the source failed (a device vanished): what it said; the folder is still finished
  std::string encoder;         // the encoder chosen, one line
};

struct RecordOptions {
  LiveEncoderSettings encoder;  // kind, bitrate, GOP, frame rate; headers are put out of band for the .mp4
  std::optional<std::filesystem::path> calibration;
  std::function<bool()> stop_requested;               // polled between frames
  std::function<void(const RecordReport&)> progress;  // after every frame
};

// Records a raw stereo source (live cameras, or a dataset replayed through the same path) into a
// VOCA video folder until the source ends or stop_requested() turns true; either way the folder
// is finished and playable. A source failing at run time (RuntimeFailure) ends the recording with
// report.error set; other errors propagate after the folder has been finished.
RecordReport recordStereo(StereoSource& source, const std::filesystem::path& out, const RecordOptions& options);

}  // namespace voca::encode
