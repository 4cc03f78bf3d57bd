#include "drivers/encode/video_folder_writer.h"

#include <fmt/core.h>

#include <exception>

#include "formats/calib/calibration_io.h"
#include "voca/core/error.h"

namespace voca::encode {

namespace fs = std::filesystem;

VideoFolderWriter::VideoFolderWriter(const fs::path& out, int width, int height, const LiveEncoderSettings& encoder,
                                     const std::optional<fs::path>& calibration)
    : out_(out) {
  if (fs::exists(out / "mav0")) {
    throw InputError(fmt::format("{}: already holds a recording (mav0/); choose a new folder", out.string()));
  }
  std::optional<StereoRig> rig;
  if (calibration) {
    rig = loadCalibration(*calibration);
    rig->requireStereo();
    for (std::size_t c = 0; c < 2; ++c) {
      const CameraCalibration& camera = rig->cameras[c];
      if (camera.width != width || camera.height != height) {
        throw InputError(fmt::format("{}: camera {} is calibrated for {}x{} but the frames are {}x{}",
                                     calibration->string(), c, camera.width, camera.height, width, height));
      }
    }
  }
  LiveEncoderSettings file_settings = encoder;
  file_settings.global_header = true;  // mp4 keeps SPS/PPS in the sample description
  std::error_code error;
  for (std::size_t c = 0; c < 2; ++c) {
    const fs::path folder = out / "mav0" / fmt::format("cam{}", c);
    fs::create_directories(folder, error);
    if (error) throw InputError(fmt::format("cannot create {}: {}", folder.string(), error.message()));
    const EncoderChoice choice = openLiveEncoder(encoders_[c], file_settings, width, height);
    file_settings.kind = choice.kind;  // both cameras on the same encoder
    encoder_description_ = choice.description;
    writers_[c] = std::make_unique<Mp4Writer>(folder / "data.mp4");
    writers_[c]->begin(encoders_[c]);
    csv_[c].open(folder / "data.csv");
    csv_[c] << "#timestamp [ns],filename\n";
    if (!csv_[c]) throw InputError(fmt::format("cannot write {}", (folder / "data.csv").string()));
  }
  if (rig) {
    // The coded size (an encoder that cannot code odd sizes codes the even crop): the intrinsics stay valid.
    for (CameraCalibration& camera : rig->cameras) {
      camera.width = encoders_[0].width();
      camera.height = encoders_[0].height();
    }
    saveBasaltCalibration(*rig, out / "calib.json");
  }
}

VideoFolderWriter::~VideoFolderWriter() {
  try {
    finish();
  } catch (const std::exception&) {
    // A destructor cannot report it; callers that care call finish() themselves.
  }
}

void VideoFolderWriter::writePackets(std::size_t camera, std::span<const EncodedPacket> packets) {
  for (const EncodedPacket& packet : packets) {
    writers_[camera]->write(packet);
    video_bytes_ += static_cast<std::int64_t>(packet.bytes.size());
  }
}

void VideoFolderWriter::write(const RawStereoFrame& frame) {
  if (finished_) throw std::logic_error("VideoFolderWriter::write after finish()");
  for (std::size_t c = 0; c < 2; ++c) {
    writePackets(c, encoders_[c].encode(frame.images[c].view(), frames_));
    csv_[c] << frame.t_ns << ',' << frame.t_ns << ".png\n";
  }
  ++frames_;
}

void VideoFolderWriter::finish() {
  if (finished_) return;
  finished_ = true;
  for (std::size_t c = 0; c < 2; ++c) {
    writePackets(c, encoders_[c].flush());
    writers_[c]->end();
    csv_[c].close();
    if (!csv_[c]) throw RuntimeFailure(fmt::format("cannot finish {}/mav0/cam{}/data.csv", out_.string(), c));
  }
}

RecordReport recordStereo(StereoSource& source, const fs::path& out, const RecordOptions& options) {
  const SourceInfo& info = source.info();
  if (info.kind != SourceKind::kRaw) {
    throw InputError(fmt::format("{}: delivers compressed video; recording takes raw frames", info.description));
  }
  VideoFolderWriter writer(out, info.width, info.height, options.encoder, options.calibration);
  RecordReport report;
  report.encoder = writer.encoderDescription();
  RawStereoFrame frame;
  for (GrayImage& image : frame.images) image.reserve(info.width, info.height);
  std::exception_ptr failure;
  try {
    while (true) {
      if (options.stop_requested && options.stop_requested()) {
        report.stopped = true;
        break;
      }
      if (!source.next(frame)) break;
      writer.write(frame);
      if (report.frames == 0) report.first_t_ns = frame.t_ns;
      report.last_t_ns = frame.t_ns;
      ++report.frames;
      report.video_bytes = writer.videoBytes();
      if (options.progress) options.progress(report);
    }
  } catch (const RuntimeFailure& e) {
    report.error = e.what();
  } catch (...) {
    failure = std::current_exception();  // finish the folder first: what was recorded stays playable
  }
  writer.finish();
  report.video_bytes = writer.videoBytes();
  report.raw_bytes = report.frames * 2 * static_cast<std::int64_t>(info.width) * info.height;
  report.source = source.counters();
  if (failure) std::rethrow_exception(failure);
  return report;
}

}  // namespace voca::encode
