#include "drivers/encode/video_file_encoder.h"

#include <chrono>
#include <optional>
#include <span>
#include <system_error>

#include <fmt/core.h>

#include "drivers/encode/mp4_writer.h"
#include "platform/filesystem/temp_dir.h"
#include "voca/core/error.h"

namespace voca::encode {
namespace {

// Removes a file unless released: no half-written video is left behind after an error.
class RemoveOnFailure {
 public:
  explicit RemoveOnFailure(std::filesystem::path path) : path_(std::move(path)) {}
  ~RemoveOnFailure() {
    if (armed_) {
      std::error_code ignored;
      std::filesystem::remove(path_, ignored);
    }
  }
  RemoveOnFailure(const RemoveOnFailure&) = delete;
  RemoveOnFailure& operator=(const RemoveOnFailure&) = delete;
  void release() { armed_ = false; }

 private:
  std::filesystem::path path_;
  bool armed_ = true;
};

}  // namespace

EncodeResult encodeVideoFile(const std::filesystem::path& path, const EncoderSettings& settings,
                             const FrameSource& source, const EncodeProgress& progress) {
  using Clock = std::chrono::steady_clock;
  EncoderSettings file_settings = settings;
  file_settings.global_header = true;  // mp4 keeps SPS/PPS in the sample description
  const int num_passes = settings.two_pass ? 2 : 1;

  std::optional<TempDir> temp;
  std::filesystem::path stats_file;
  if (num_passes == 2) {
    temp.emplace("voca-encode");
    stats_file = temp->path() / "pass1.log";
  }

  Mp4Writer writer(path);
  RemoveOnFailure cleanup(path);
  EncodeResult result;
  int first_pass_frames = -1;

  for (int pass_index = 1; pass_index <= num_passes; ++pass_index) {
    const bool final_pass = pass_index == num_passes;
    const EncoderPass pass =
        num_passes == 1 ? EncoderPass::kSingle : (final_pass ? EncoderPass::kSecond : EncoderPass::kFirst);
    VideoEncoder encoder;
    int frame_index = 0;
    Clock::duration encode_time{};

    const auto consume = [&](std::span<const EncodedPacket> packets) {
      if (!final_pass) return;
      for (const EncodedPacket& packet : packets) {
        writer.write(packet);
        result.payload_bytes += static_cast<std::int64_t>(packet.bytes.size());
        result.num_keyframes += packet.keyframe ? 1 : 0;
      }
    };
    source([&](GrayView image) {
      if (!encoder.isOpen()) {
        encoder.open(file_settings, image.width, image.height, pass, stats_file);
        if (final_pass) writer.begin(encoder);
      }
      const Clock::time_point start = Clock::now();
      const std::span<const EncodedPacket> packets = encoder.encode(image, frame_index);
      encode_time += Clock::now() - start;
      consume(packets);
      ++frame_index;
      if (progress) progress(pass_index, num_passes, frame_index - 1);
    });
    if (frame_index == 0) throw InputError(fmt::format("no frames to encode into {}", path.string()));
    if (first_pass_frames >= 0 && frame_index != first_pass_frames) {
      throw InputError(
          fmt::format("the frame source gave {} frames in pass 1 but {} in pass 2", first_pass_frames, frame_index));
    }
    first_pass_frames = frame_index;
    const Clock::time_point start = Clock::now();
    const std::span<const EncodedPacket> tail = encoder.flush();
    encode_time += Clock::now() - start;
    consume(tail);
    result.pass_ms_per_frame.push_back(std::chrono::duration<double, std::milli>(encode_time).count() / frame_index);
    result.num_frames = frame_index;
    result.width = encoder.width();
    result.height = encoder.height();
  }
  writer.end();
  cleanup.release();

  result.file_bytes = static_cast<std::int64_t>(std::filesystem::file_size(path));
  result.duration_s = result.num_frames * static_cast<double>(settings.fps_den) / settings.fps_num;
  result.achieved_bitrate_bps = static_cast<double>(result.payload_bytes) * 8.0 / result.duration_s;
  return result;
}

}  // namespace voca::encode
