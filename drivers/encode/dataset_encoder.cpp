// Datasets -> VOCA video folders.

#include "drivers/encode/dataset_encoder.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>
#include <system_error>
#include <utility>

#include <fmt/core.h>

#include "drivers/decode/video_reader.h"
#include "formats/calib/calibration_io.h"
#include "formats/image/png_io.h"
#include "formats/trajectory/trajectory_io.h"
#include "platform/filesystem/output_paths.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"

namespace voca::encode {

namespace fs = std::filesystem;

namespace {

// Decodes a camera's video with the one decoder and hands out its Y planes: the input side when
// re-encoding a VOCA video folder. The Y plane is what our tracker sees, so it is re-encoded as is
// (no range conversion).
void decodeLuma(const Dataset& dataset, const fs::path& path, int max_frames,
                const std::function<void(GrayView)>& emit) {
  decode::DecoderOptions options;
  options.kind = decode::DecoderKind::kSoftware;
  options.export_motion = false;
  options.strict = false;  // a damaged picture is re-encoded as the decoder conceals it
  options.log_choice = false;
  decode::VideoReader reader(path, decode::datasetTimestamps(dataset), options);
  decode::DecodedFrame frame;
  int emitted = 0;
  while (emitted < max_frames && reader.next(frame)) {
    emit(frame.luma.view());
    ++emitted;
  }
  if (emitted < max_frames) {
    throw InputError(fmt::format("{}: holds {} frames but data.csv lists {}", path.string(), emitted, max_frames));
  }
}

std::int64_t fileSize(const fs::path& path) {
  std::error_code error;
  const auto size = fs::file_size(path, error);
  return error ? 0 : static_cast<std::int64_t>(size);
}

void createFolder(const fs::path& folder) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error || !fs::is_directory(folder)) {
    throw InputError(fmt::format("cannot create the output folder {}: {}", folder.string(),
                                 error ? error.message() : "a file of that name exists"));
  }
}

// Thrown out of the per-frame progress when options.stop_requested says so; encodeDataset turns it
// into report.stopped after the outputs were cleaned up.
struct EncodingStopped {};

// What one encoding adds to the output folder, taken away again when it fails: a failed run leaves
// neither an empty folder nor one camera's video without the other's. Files are written under
// temporary names and renamed into place by commit(), so until then what was there before, a
// previous encoding included, stays as it was.
class CreatedOutputs {
 public:
  CreatedOutputs() = default;
  CreatedOutputs(const CreatedOutputs&) = delete;
  CreatedOutputs& operator=(const CreatedOutputs&) = delete;
  ~CreatedOutputs() {
    for (auto it = created_.rbegin(); it != created_.rend(); ++it) {
      std::error_code ignored;
      fs::remove_all(*it, ignored);
    }
  }

  // Creates the folder and its missing parents, remembering the outermost of them.
  void folder(const fs::path& folder) {
    fs::path outermost;
    for (fs::path p = folder; !p.empty() && !fs::exists(p); p = p.parent_path()) {
      outermost = p;
      if (p == p.parent_path()) break;
    }
    // Remembered first: a creation that fails half way leaves parents behind too.
    if (!outermost.empty()) created_.push_back(outermost);
    createFolder(folder);
  }
  // The name to write `final_path` under until commit(): data.mp4 -> data.partial.mp4, beside it
  // (one file system, so the rename cannot copy) and with its extension (muxers go by it).
  fs::path staged(const fs::path& final_path) {
    fs::path staged_path = final_path;
    staged_path.replace_filename(final_path.stem().string() + ".partial" + final_path.extension().string());
    created_.push_back(staged_path);
    staged_.emplace_back(staged_path, final_path);
    return staged_path;
  }
  // The run succeeded: the staged files replace their final names, and everything is kept.
  void commit() {
    for (const auto& [staged_path, final_path] : staged_) fs::rename(staged_path, final_path);
    created_.clear();
  }

 private:
  std::vector<fs::path> created_;
  std::vector<std::pair<fs::path, fs::path>> staged_;  // (temporary name, final name)
};

}  // namespace

void datasetFrameRate(const Dataset& dataset, int& fps_num, int& fps_den) {
  if (dataset.frames.size() < 2) {
    throw InputError(fmt::format("{}: a frame rate needs at least two frames", dataset.root.string()));
  }
  std::vector<std::int64_t> intervals;
  for (std::size_t i = 1; i < dataset.frames.size(); ++i) {
    intervals.push_back(dataset.frames[i].t_ns - dataset.frames[i - 1].t_ns);
  }
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  const double interval_ns = static_cast<double>(intervals[intervals.size() / 2]);
  if (interval_ns <= 0) throw InputError(fmt::format("{}: timestamps do not increase", dataset.root.string()));
  const double fps = 1e9 / interval_ns;
  // Clock jitter of a few microseconds per frame stays far below 0.05 %.
  const auto near = [](double value, double whole) { return whole >= 1.0 && std::fabs(value - whole) <= 5e-4 * value; };
  if (near(fps, std::round(fps))) {
    fps_num = static_cast<int>(std::round(fps));
    fps_den = 1;
  } else if (near(fps * 1.001, std::round(fps * 1.001))) {  // NTSC-style rates, which MPEG-2 requires exactly
    fps_num = static_cast<int>(std::round(fps * 1.001)) * 1000;
    fps_den = 1001;
  } else {
    const int millihertz = static_cast<int>(std::lround(fps * 1000.0));
    const int divisor = std::gcd(millihertz, 1000);
    fps_num = millihertz / divisor;
    fps_den = 1000 / divisor;
  }
}

DatasetEncodeReport encodeDataset(const fs::path& input, const fs::path& out, const DatasetEncodeOptions& options,
                                  const DatasetEncodeProgress& progress, const DatasetEncodeWarning& warn) {
  const Dataset dataset = openDataset(input);
  DatasetEncodeReport report;
  report.input_layout = dataset.layout;
  report.num_frames = static_cast<int>(dataset.frames.size());
  const auto addWarning = [&](std::string warning) {
    if (warn) warn(warning);
    report.warnings.push_back(std::move(warning));
  };
  // Frames the dataset leaves out (rows without an image, unpaired timestamps) are said before the
  // long encoding, so they are seen even when it fails.
  for (const std::string& warning : dataset.warnings) addWarning(warning);

  if (options.cameras.empty()) throw InputError("no camera selected (--cameras takes 0, 1 or 0,1)");
  for (std::size_t i = 0; i < options.cameras.size(); ++i) {
    const int camera = options.cameras[i];
    if (camera != 0 && camera != 1) {
      throw InputError(fmt::format("camera {}: a stereo dataset has cameras 0 (left) and 1 (right)", camera));
    }
    if (std::count(options.cameras.begin(), options.cameras.end(), camera) > 1) {
      throw InputError(fmt::format("camera {} is listed twice", camera));
    }
  }
  requireFoldersApart({"the output folder", out}, {"the input dataset", dataset.root});

  EncoderSettings settings = options.settings;
  // A single frame has no rate of its own and takes the encoding's; --fps dataset needs two and says so.
  report.dataset_fps_num = settings.fps_num;
  report.dataset_fps_den = settings.fps_den;
  if (options.use_dataset_fps || dataset.frames.size() >= 2) {
    datasetFrameRate(dataset, report.dataset_fps_num, report.dataset_fps_den);
  }
  if (options.use_dataset_fps) {
    settings.fps_num = report.dataset_fps_num;
    settings.fps_den = report.dataset_fps_den;
  }
  report.fps_num = settings.fps_num;
  report.fps_den = settings.fps_den;
  {
    // Codec, rate and x264 options are checked on a small frame before any folder is created.
    VideoEncoder probe;
    probe.open(settings, 64, 64);
  }

  // Load the calibration before the long encoding so that a bad file fails early.
  std::optional<StereoRig> rig;
  const std::optional<fs::path> calibration_file = options.calibration ? options.calibration : dataset.calibration;
  if (calibration_file) rig = loadCalibration(*calibration_file);
  // Its image size too: the folder written with another size is one that `voca run` refuses.
  if (rig && dataset.layout != DatasetLayout::kVocaVideo && !dataset.frames.empty()) {
    GrayImage first;
    for (int camera : options.cameras) {
      if (camera >= static_cast<int>(rig->cameras.size())) continue;
      const fs::path& file = camera == 0 ? dataset.frames.front().left : dataset.frames.front().right;
      try {
        readPngGray(file, first);
      } catch (const InputError&) {
        continue;  // the encoding names the unreadable frame, with what to do about it
      }
      const CameraCalibration& calib = rig->cameras[static_cast<std::size_t>(camera)];
      if (calib.width != first.width() || calib.height != first.height()) {
        throw InputError(
            fmt::format("{}: camera {} is calibrated for {}x{} images, but {} is {}x{}; pass the "
                        "calibration of these cameras with --calib",
                        calibration_file->string(), camera, calib.width, calib.height, file.string(), first.width(),
                        first.height()));
      }
    }
  }

  try {
    CreatedOutputs created;
    const fs::path mav0 = out / "mav0";
    for (int camera : options.cameras) {
      const fs::path cam_dir = mav0 / fmt::format("cam{}", camera);
      created.folder(cam_dir);
      CameraEncodeReport cam_report;
      cam_report.camera = camera;
      cam_report.video = cam_dir / "data.mp4";

      FrameSource source;
      if (dataset.layout == DatasetLayout::kVocaVideo) {
        const fs::path video = camera == 0 ? dataset.video_left : dataset.video_right;
        cam_report.input_bytes = fileSize(video);
        source = [&, video](const std::function<void(GrayView)>& emit) {
          decodeLuma(dataset, video, report.num_frames, emit);
        };
      } else {
        for (const StereoFrameRef& frame : dataset.frames) {
          cam_report.input_bytes += fileSize(camera == 0 ? frame.left : frame.right);
        }
        source = [&, camera](const std::function<void(GrayView)>& emit) {
          GrayImage image;
          std::pair<int, int> first_size;
          for (std::size_t i = 0; i < dataset.frames.size(); ++i) {
            const StereoFrameRef& frame = dataset.frames[i];
            const std::filesystem::path& file = camera == 0 ? frame.left : frame.right;
            try {
              readPngGray(file, image);
            } catch (const InputError& e) {
              // Fatal, unlike `voca run`'s skip: the video and data.csv would silently lack the frame.
              throw InputError(
                  fmt::format("{} (frame {} of cam{}); remove the file to leave the frame out with a warning", e.what(),
                              i, camera));
            }
            // The encoder would refuse the frame too, but it knows sizes, not files.
            if (i == 0) {
              first_size = {image.width(), image.height()};
            } else if (std::pair{image.width(), image.height()} != first_size) {
              throw InputError(fmt::format("{}: {}x{} pixels, but the camera's first image is {}x{}", file.string(),
                                           image.width(), image.height(), first_size.first, first_size.second));
            }
            emit(image.view());
          }
        };
      }
      std::int64_t raw_bytes = 0;
      const FrameSource counted = [&](const std::function<void(GrayView)>& emit) {
        raw_bytes = 0;
        source([&](GrayView image) {
          raw_bytes += static_cast<std::int64_t>(image.width) * image.height;
          emit(image);
        });
      };
      cam_report.result = encodeVideoFile(created.staged(cam_report.video), settings, counted,
                                          [&](int pass, int num_passes, int frame_index) {
                                            if (options.stop_requested && options.stop_requested())
                                              throw EncodingStopped{};
                                            if (progress)
                                              progress(camera, pass, num_passes, frame_index, report.num_frames);
                                          });

      // The frames of the video, in order, with their original timestamps.
      const fs::path csv_path = cam_dir / "data.csv";
      const fs::path csv_staged = created.staged(csv_path);
      std::ofstream csv(csv_staged);
      csv << "#timestamp [ns],filename\n";
      for (const StereoFrameRef& frame : dataset.frames) csv << frame.t_ns << ',' << frame.t_ns << ".png\n";
      csv.close();
      if (!csv) throw InputError(fmt::format("cannot write {}", csv_path.string()));

      report.input_bytes += cam_report.input_bytes;
      report.output_bytes += cam_report.result.file_bytes;
      report.raw_bytes += raw_bytes;
      report.cameras.push_back(std::move(cam_report));
    }

    if (dataset.ground_truth) {
      const fs::path gt_dir = mav0 / "state_groundtruth_estimate0";
      created.folder(gt_dir);
      const fs::path gt_out = gt_dir / "data.csv";
      const fs::path gt_staged = created.staged(gt_out);
      if (dataset.layout == DatasetLayout::kKitti) {
        // KITTI poses have no timestamps of their own: pair them with times.txt. With a KITTI
        // calibration the body frame is cam0, so the camera pose is the body pose.
        const Trajectory poses =
            loadTrajectory(*dataset.ground_truth, TrajectoryFormat::kKitti, dataset.root / "times.txt");
        saveTrajectory(poses, gt_staged, TrajectoryFormat::kEuroc);
      } else {
        std::error_code error;
        fs::copy_file(*dataset.ground_truth, gt_staged, fs::copy_options::overwrite_existing, error);
        if (error)
          throw InputError(fmt::format("cannot copy {} to {}: {}", dataset.ground_truth->string(), gt_out.string(),
                                       error.message()));
      }
      report.ground_truth_written = gt_out;
    }

    if (rig) {
      // Every size is coded as it is (odd ones included), so the calibration carries over unchanged.
      for (const CameraEncodeReport& cam : report.cameras) {
        if (cam.camera >= static_cast<int>(rig->cameras.size())) continue;
        const CameraCalibration& calib = rig->cameras[static_cast<std::size_t>(cam.camera)];
        if (calib.width != cam.result.width || calib.height != cam.result.height) {
          addWarning(fmt::format("the calibration of cam{} is for {}x{} images but the images are {}x{}", cam.camera,
                                 calib.width, calib.height, cam.result.width, cam.result.height));
        }
      }
      const fs::path calib_out = out / "calib.json";
      saveBasaltCalibration(*rig, created.staged(calib_out));
      report.calibration_written = calib_out;
    } else {
      addWarning("no calibration found with the dataset and none given (--calib): no calib.json written");
    }
    if (options.cameras.size() < 2) {
      addWarning("only one camera encoded: the folder is not a stereo VOCA video dataset");
    }
    created.commit();
  } catch (const EncodingStopped&) {
    // Everything this run wrote is gone (CreatedOutputs); what was there before is untouched.
    DatasetEncodeReport stopped;
    stopped.input_layout = report.input_layout;
    stopped.num_frames = report.num_frames;
    stopped.warnings = std::move(report.warnings);
    stopped.stopped = true;
    return stopped;
  }
  return report;
}

DatasetEncodeProgress progressOnLine(platform::ProgressLine& line) {
  return [&line, last_percent = -1](int camera, int pass, int passes, int frame, int frames) mutable {
    const int percent = 100 * (frame + 1) / frames;
    if (percent == last_percent && frame + 1 != frames) return;
    last_percent = percent;
    line.update("cam{} pass {}/{}: frame {}/{} ({}%)", camera, pass, passes, frame + 1, frames, percent);
    if (frame + 1 == frames) line.end();
  };
}

bool encodeForReplay(const fs::path& input, const fs::path& out, std::int64_t bitrate_bps,
                     const std::optional<fs::path>& calibration, bool progress,
                     const std::function<bool()>& stop_requested, int keyframe_interval) {
  DatasetEncodeOptions options;
  options.settings.bitrate_bps = bitrate_bps;
  if (keyframe_interval > 0) {
    std::string& params = options.settings.x264_params;
    const std::string keyint = fmt::format("keyint={}", keyframe_interval);
    const std::size_t at = params.find("keyint=");
    if (at == std::string::npos) {
      params += ":" + keyint;
    } else {
      const std::size_t end = params.find(':', at);
      params.replace(at, end == std::string::npos ? std::string::npos : end - at, keyint);
    }
  }
  options.calibration = calibration;
  options.stop_requested = stop_requested;
  silenceCodecLogs();
  // Ended by its destructor, also when an exception leaves: the caller's message starts a line.
  platform::ProgressLine line;
  const DatasetEncodeReport report = encodeDataset(input, out, options, progress ? progressOnLine(line) : nullptr);
  return !report.stopped;
}

}  // namespace voca::encode
