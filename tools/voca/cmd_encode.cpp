// `voca encode`: a raw stereo dataset (or a VOCA video folder) -> the VOCA video layout, with the
// paper's two-pass constant-bitrate H.264 encoding.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fmt/core.h>

#include "drivers/decode/decoded_dataset.h"
#include "drivers/encode/dataset_encoder.h"
#include "platform/filesystem/output_paths.h"
#include "platform/realtime/stop_signal.h"
#include "platform/terminal/progress_line.h"
#include "tools/voca/command.h"
#include "voca/core/error.h"

namespace {

struct EncodeOptions {
  std::string dataset;
  std::string out;
  std::string bitrate = "500k";
  std::string fps = "30";
  std::string cameras = "0,1";
  std::string codec = "libx264";
  std::string pix_fmt = "yuv420p";
  std::string calib;
  std::string decoded_png;
  bool single_pass = false;
  int threads = 1;
};

// "0,1" -> {0, 1}.
std::vector<int> parseCameras(const std::string& text) {
  std::vector<int> cameras;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    if (item != "0" && item != "1") {
      throw voca::InputError(fmt::format("--cameras '{}': expected a comma-separated list of 0 and 1, e.g. 0,1", text));
    }
    cameras.push_back(item[0] - '0');
    start = comma + 1;
  }
  return cameras;
}

// "30", "20", "30000/1001" or "dataset".
void parseFps(const std::string& text, voca::encode::DatasetEncodeOptions& options) {
  if (text == "dataset") {
    options.use_dataset_fps = true;
    return;
  }
  const auto bad = [&] {
    return voca::InputError(
        fmt::format("--fps '{}': expected 'dataset', a whole rate such as 30, or a fraction such as 30000/1001", text));
  };
  const auto parsePositive = [&](const std::string& digits) {
    if (digits.empty() || digits.size() > 6 || digits.find_first_not_of("0123456789") != std::string::npos) throw bad();
    const int value = std::stoi(digits);
    if (value <= 0) throw bad();
    return value;
  };
  const std::size_t slash = text.find('/');
  options.settings.fps_num = parsePositive(text.substr(0, slash));
  options.settings.fps_den = slash == std::string::npos ? 1 : parsePositive(text.substr(slash + 1));
}

// Thrown out of the --decoded-png progress when a signal asks to stop.
struct DecodingStopped {};

std::string megabytesText(std::int64_t bytes) { return fmt::format("{:.2f} MB", static_cast<double>(bytes) / 1e6); }

// 20 or 29.970: a frame rate as a person reads it.
std::string fpsText(int num, int den) {
  return den == 1 ? fmt::format("{}", num) : fmt::format("{:.3f}", static_cast<double>(num) / den);
}

int runEncode(const EncodeOptions& cli) {
  using namespace voca::encode;
  DatasetEncodeOptions options;
  options.settings.codec = cli.codec;
  options.settings.monochrome = cli.pix_fmt == "gray";
  if (options.settings.monochrome && cli.codec != "libx264") {
    throw voca::InputError(
        fmt::format("--pix-fmt gray: only libx264 codes frames without chroma; --codec {} takes yuv420p", cli.codec));
  }
  options.settings.bitrate_bps = parseBitrate(cli.bitrate);
  options.settings.two_pass = !cli.single_pass;
  if (cli.threads < 0) throw voca::InputError(fmt::format("--threads {}: expected 0 (automatic) or more", cli.threads));
  options.settings.threads = cli.threads;
  parseFps(cli.fps, options);
  options.cameras = parseCameras(cli.cameras);
  if (!cli.calib.empty()) options.calibration = cli.calib;
  if (!cli.decoded_png.empty()) {
    // Checked before the long encoding: the decoded frames are written after it.
    if (options.cameras.size() != 2) throw voca::InputError("--decoded-png needs both cameras (--cameras 0,1)");
    voca::requireFoldersApart({"--decoded-png", cli.decoded_png}, {"the input dataset", cli.dataset});
    voca::requireFoldersApart({"--decoded-png", cli.decoded_png}, {"the output folder", cli.out});
  }
  silenceCodecLogs();
  // A signal ends the encoding the clean way: the files of this run are removed and a previous
  // encoding in the same folder stays as it was (a second signal still exits at once).
  voca::platform::installStopHandlers();
  options.stop_requested = voca::platform::stopRequested;

  const auto start = std::chrono::steady_clock::now();
  voca::platform::ProgressLine progress;
  const DatasetEncodeReport report =
      encodeDataset(cli.dataset, cli.out, options, voca::encode::progressOnLine(progress),
                    [&](const std::string& warning) { progress.message("warning: {}", warning); });
  if (report.stopped) {
    progress.end();
    const bool existed = std::filesystem::exists(std::filesystem::path(cli.out) / "mav0");
    fmt::print(stderr, "voca encode: stopped by a signal before the encoding finished; nothing was written{}\n",
               existed ? fmt::format(" ({} holds what it held before)", cli.out) : "");
    return voca::platform::interruptedExitCode(voca::platform::stopSignal());
  }
  fmt::print("input      {} ({} layout), {} frames\n", cli.dataset, voca::layoutName(report.input_layout),
             report.num_frames);
  fmt::print("output     {}/mav0/cam*/data.mp4 ({}, {} bit/s target, {} fps, {}{})\n", cli.out, cli.codec,
             options.settings.bitrate_bps, fpsText(report.fps_num, report.fps_den),
             options.settings.two_pass ? "two-pass" : "one-pass", options.settings.monochrome ? ", gray 4:0:0" : "");
  for (const CameraEncodeReport& cam : report.cameras) {
    const EncodeResult& r = cam.result;
    std::string pass_times;
    for (std::size_t p = 0; p < r.pass_ms_per_frame.size(); ++p) {
      pass_times += fmt::format("{}pass {} {:.2f} ms/frame", p == 0 ? "" : ", ", p + 1, r.pass_ms_per_frame[p]);
    }
    fmt::print("cam{}       {}x{}, {} -> {} ({:.1f}x), achieved {:.1f} kbit/s, {} keyframe(s), encode {}\n", cam.camera,
               r.width, r.height, megabytesText(cam.input_bytes), megabytesText(r.file_bytes),
               static_cast<double>(cam.input_bytes) / static_cast<double>(r.file_bytes),
               r.achieved_bitrate_bps / 1000.0, r.num_keyframes, pass_times);
  }
  if (!report.timedAtDatasetRate()) {
    // The paper's convention (bits per frame = bitrate / 30) gives another bitrate over the dataset's
    // real time, which is what a stream of these frames at their own rate would take.
    std::string real_time;
    for (const CameraEncodeReport& cam : report.cameras) {
      real_time += fmt::format("{}cam{} {:.1f} kbit/s", real_time.empty() ? "" : ", ", cam.camera,
                               cam.result.achieved_bitrate_bps * report.realTimeRateScale() / 1000.0);
    }
    fmt::print(
        "real time  {} at the dataset's own {} fps (the videos are timed at {}; --fps dataset encodes at "
        "the dataset's rate)\n",
        real_time, fpsText(report.dataset_fps_num, report.dataset_fps_den), fpsText(report.fps_num, report.fps_den));
  }
  for (const CameraEncodeReport& cam : report.cameras) {
    const double deviation = cam.result.achieved_bitrate_bps / static_cast<double>(options.settings.bitrate_bps) - 1.0;
    // Two-pass x264 lands within a few percent; more means the codec hit its quantiser limits
    // (MPEG-4/MPEG-2 at q=31 on large frames, or very simple content) or one-pass rate control.
    if (std::abs(deviation) > 0.1) {
      fmt::print(stderr, "warning: cam{}'s achieved bitrate is {:.0f}% {} the target\n", cam.camera,
                 100.0 * std::abs(deviation), deviation > 0 ? "above" : "below");
    }
  }
  fmt::print("total      {} -> {}: compression ratio {:.1f}x ({:.1f}x against raw 8-bit frames)\n",
             megabytesText(report.input_bytes), megabytesText(report.output_bytes),
             static_cast<double>(report.input_bytes) / static_cast<double>(report.output_bytes),
             static_cast<double>(report.raw_bytes) / static_cast<double>(report.output_bytes));
  if (report.ground_truth_written) fmt::print("ground truth -> {}\n", report.ground_truth_written->string());
  if (report.calibration_written) fmt::print("calibration  -> {}\n", report.calibration_written->string());
  if (!cli.decoded_png.empty()) {
    voca::decode::DecodedDatasetReport decoded;
    try {
      decoded = voca::decode::writeDecodedEuroc(cli.out, cli.decoded_png, [&](std::int64_t done, std::int64_t total) {
        if (voca::platform::stopRequested()) throw DecodingStopped{};
        if (done % 50 == 0 || done == total) progress.update("decoding to PNG: frame {}/{}", done, total);
        if (done == total) progress.end();
      });
    } catch (const DecodingStopped&) {
      progress.end();
      fmt::print(stderr,
                 "voca encode: stopped by a signal while writing --decoded-png: the videos in {} are complete, "
                 "the PNG folder {} is not\n",
                 cli.out, cli.decoded_png);
      return voca::platform::interruptedExitCode(voca::platform::stopSignal());
    }
    fmt::print("decoded    {} frames ({}x{}) as a EuRoC folder -> {}{}\n", decoded.frames, decoded.width,
               decoded.height, cli.decoded_png,
               decoded.calibration_copied ? " (with calib.json and ground truth)" : "");
  }
  fmt::print("done in {:.1f} s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}

const bool encode_command_registered = voca::cli::registerCommand(
    {.name = "encode",
     .summary = "Encode a stereo dataset into the VOCA video layout (one H.264 .mp4 per camera)",
     .order = 20,
     .configure = [](CLI::App& app) -> voca::cli::Runner {
       auto options = std::make_shared<EncodeOptions>();
       app.description(
           "Encodes a raw EuRoC / TUM-VI / KITTI dataset, or re-encodes a VOCA video folder, into\n"
           "<out>/mav0/camN/data.mp4 + data.csv (original timestamps), with ground truth and calib.json.\n"
           "Default: the VOCA paper's encoding (libx264, two-pass 500 kbit/s, 30 fps, yuv420p,\n"
           "partitions=p8x8,p4x4,i8x8:keyint=1000:me=umh:merange=64:subme=6:bframes=0:ref=1).");
       app.add_option("dataset", options->dataset,
                      "Input dataset folder (EuRoC/TUM-VI root or mav0, KITTI sequence, "
                      "or a VOCA video folder)")
           ->required();
       app.add_option("--out,-o", options->out,
                      "Output folder (created; the videos, ground truth and calib.json of an earlier encoding there "
                      "are replaced once this one succeeds)")
           ->required();
       app.add_option("--bitrate,-b", options->bitrate, "Target bitrate per camera: 500k, 1M, 1000000")
           ->capture_default_str();
       app.add_option("--fps", options->fps,
                      "Encoding frame rate: a number (30, 20, 30000/1001) or 'dataset' for the dataset's own rate. "
                      "The official VOCA code uses 30 for every dataset, so bits per frame = bitrate / 30")
           ->capture_default_str();
       app.add_option("--cameras", options->cameras, "Cameras to encode: 0, 1 or 0,1")->capture_default_str();
       app.add_option("--codec", options->codec, "libx264 (H.264, the paper), mpeg4 (MPEG-4 Part 2) or mpeg2video")
           ->capture_default_str()
           ->check(CLI::IsMember({"libx264", "mpeg4", "mpeg2video"}));
       app.add_option("--pix-fmt", options->pix_fmt,
                      "yuv420p (the paper: luma plus neutral chroma) or gray (libx264 only: luma alone, 4:0:0; "
                      "software decoders then skip the chroma planes, about a tenth of a decode, but hardware "
                      "decoders commonly take 4:2:0 only; odd frame sizes are always gray)")
           ->capture_default_str()
           ->check(CLI::IsMember({"yuv420p", "gray"}));
       app.add_option("--calib", options->calib,
                      "Calibration to write as <out>/calib.json (Basalt .json, Kalibr .yaml, KITTI calib.txt); "
                      "default: the one found with the dataset");
       app.add_option("--decoded-png", options->decoded_png,
                      "Also decode the new videos into this EuRoC folder (PNG frames, data.csv, ground truth, "
                      "calib.json): exactly the pixels VOCA-RT sees, for running other systems on the same input");
       app.add_flag("--single-pass", options->single_pass, "One-pass rate control (faster, less exact bitrate)");
       app.add_option("--threads", options->threads,
                      "Encoder threads; 0 = automatic (faster, but x264's output then depends on the core count)")
           ->capture_default_str();
       return [options] { return runEncode(*options); };
     }});

}  // namespace
