#include "pipeline/demo/demo_runner.h"

#include <fmt/core.h>
#include <fmt/format.h>

#include <chrono>
#include <fstream>
#include <system_error>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "pipeline/synth/synth_runner.h"
#include "pipeline/vo/vo_runner.h"
#include "voca/core/error.h"

namespace voca::pipeline {
namespace {

namespace fs = std::filesystem;

// The settings a step ran with, kept beside the demo's output (one value a line): reuse takes what is
// there, and the summary must describe that, not the options of this call.
std::vector<std::string> readSettings(const fs::path& file) {
  std::vector<std::string> values;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) values.push_back(line);
  return values;
}

void writeSettings(const fs::path& file, const std::vector<std::string>& values) {
  std::ofstream out(file);
  for (const std::string& value : values) out << value << '\n';
}

// Replaces `used` (the settings asked for) with those recorded in `file`, warning when they differ.
void takeRecordedSettings(const fs::path& folder, const fs::path& file, std::vector<std::string>& used,
                          const char* options) {
  const std::vector<std::string> asked = used;
  used = readSettings(file);
  if (!used.empty() && used != asked) {
    fmt::print(stderr, "warning: --reuse: {} was made with {} {}, not as asked; drop --reuse to make it again\n",
               folder.string(), options, fmt::join(used, " "));
  }
}

bool runEnded(const VoRunResult& result) { return result.pipeline_report.error || result.stop_signal != 0; }

}  // namespace

void checkDemoOptions(const DemoOptions& o) {
  if (o.seconds < 2.0 || o.seconds > 120.0) throw InputError("--seconds: expected 2 to 120");
  if (o.threads < 1) throw InputError(fmt::format("--threads {}: expected 1 or more", o.threads));
  encode::parseBitrate(o.bitrate);
}

DemoResult runDemo(const DemoOptions& o) {
  // Checked before the folder is made (the steps would check them only after).
  checkDemoOptions(o);
  const std::int64_t bitrate_bps = encode::parseBitrate(o.bitrate);
  const auto start = std::chrono::steady_clock::now();
  const std::function<bool()> stop_requested = o.stop_requested ? o.stop_requested : [] { return false; };

  DemoResult demo;
  demo.raw = o.out / "synth";
  demo.video = o.out / "video";
  fs::create_directories(o.out);
  const bool have_raw = fs::exists(demo.raw / "calib.json");
  const fs::path render_file = o.out / "synth.settings", encode_file = o.out / "video.settings";
  demo.rendered = {o.motion, fmt::format("{}", o.seconds)};
  demo.encoded = {o.bitrate};
  std::error_code ignored;

  if (!(o.reuse && have_raw)) {
    fmt::print(stderr, "[1/4] rendering {} s of {} motion into {}\n", o.seconds, o.motion, demo.raw.string());
    fs::remove(render_file, ignored);
    fs::remove_all(demo.raw, ignored);
    SynthOptions synth;
    synth.out = demo.raw;
    synth.motion = o.motion;
    synth.seconds = o.seconds;
    synth.supersample = 2;
    synth.threads = o.threads;
    synth.stop_requested = stop_requested;
    const SynthResult rendered = synthesizeSequence(synth);
    if (rendered.stopped) {
      fs::remove_all(demo.raw, ignored);
      demo.end = DemoResult::End::kStoppedRendering;
      return demo;
    }
    writeSettings(render_file, demo.rendered);
  } else {
    fmt::print(stderr, "[1/4] reusing {}\n", demo.raw.string());
    takeRecordedSettings(demo.raw, render_file, demo.rendered, "--motion and --seconds");
  }

  if (!(o.reuse && have_raw && fs::exists(demo.video / "mav0" / "cam1" / "data.mp4"))) {
    fmt::print(stderr, "[2/4] encoding both cameras at {} (two-pass x264, the paper's settings) into {}\n", o.bitrate,
               demo.video.string());
    fs::remove(encode_file, ignored);
    if (!encode::encodeForReplay(demo.raw, demo.video, bitrate_bps, std::nullopt, true, stop_requested)) {
      demo.end = DemoResult::End::kStoppedEncoding;
      return demo;
    }
    writeSettings(encode_file, demo.encoded);
  } else {
    fmt::print(stderr, "[2/4] reusing {}\n", demo.video.string());
    takeRecordedSettings(demo.video, encode_file, demo.encoded, "--bitrate");
  }

  fmt::print(stderr, "[3/4] running the VO on the decoded video: baseline and VOCA\n");
  for (const PriorMode mode : {PriorMode::kNone, PriorMode::kMvParallelOf}) {
    DemoRun run;
    run.mode = mode;
    run.label = fmt::format("{} ({})", mode == PriorMode::kNone ? "baseline" : "VOCA", priorModeName(mode));
    run.trajectory = o.out / fmt::format("traj_{}.txt", priorModeName(mode));
    VoRunOptions options;
    options.input = demo.video;
    options.mode = mode;
    options.progress = false;
    options.trajectory_file = run.trajectory;
    options.view = o.view;
    options.mcap = mode == PriorMode::kNone ? o.baseline_mcap : o.voca_mcap;
    run.result = runVisualOdometry(options);
    if (runEnded(run.result)) {
      demo.ended_run = std::move(run.result);
      demo.end = DemoResult::End::kRunEnded;
      return demo;
    }
    for (const std::string& warning : run.result.warnings) fmt::print(stderr, "warning: {}\n", warning);
    demo.runs.push_back(std::move(run));
  }

  demo.overlay = o.out / fmt::format("overlay_{}.mp4", priorModeName(PriorMode::kMvParallelOf));
  fmt::print(stderr, "[4/4] overlay of the VOCA tracks into {}\n", demo.overlay.string());
  VoRunOptions overlay;
  overlay.input = demo.video;
  overlay.mode = PriorMode::kMvParallelOf;
  overlay.estimate = false;
  overlay.progress = false;
  overlay.overlay_file = demo.overlay;
  VoRunResult tracked = runVisualOdometry(overlay);
  if (runEnded(tracked)) {
    demo.ended_run = std::move(tracked);
    demo.end = DemoResult::End::kRunEnded;
    return demo;
  }
  demo.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return demo;
}

}  // namespace voca::pipeline
