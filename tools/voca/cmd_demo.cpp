// `voca demo`: the README's main job in one command. Renders a short synthetic stereo sequence with
// fast motion, encodes it at 500 kbit/s, runs the baseline tracker (no priors) and VOCA (motion
// vectors in parallel with optical flow) through the whole VO, and prints both side by side, with
// the trajectories and an overlay video of the tracks written beside.

#include <fmt/core.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "drivers/encode/video_encoder.h"
#include "pipeline/vo/vo_runner.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "tools/voca/view_cli.h"
#include "voca/core/error.h"

namespace {

using voca::cli::Runner;
namespace fs = std::filesystem;

struct DemoOptions {
  std::string out = "voca-demo";
  double seconds = 6.0;
  std::string motion = "fast-rotation";
  std::string bitrate = "500k";
  int threads = 2;
  bool reuse = false;
  voca::cli::ViewCli view;
};

// Runs another registered subcommand (synth, encode, track) as if typed on the command line, so the
// demo uses exactly the machinery users run by hand.
// Its exit code; a failure throws, a stop by a signal returns the signal's exit code.
int runSubcommand(const std::string& name, std::vector<std::string> args) {
  for (const voca::cli::CommandSpec& spec : voca::cli::registeredCommands()) {
    if (spec.name != name) continue;
    CLI::App app{spec.summary, name};
    const Runner run = spec.configure(app);
    std::reverse(args.begin(), args.end());  // CLI11 takes the argument vector back to front
    try {
      app.parse(args);
    } catch (const CLI::ParseError& e) {
      throw voca::RuntimeFailure(fmt::format("voca {}: {}", name, e.what()));
    }
    const int code = run();
    if (code != 0 && voca::platform::stopRequested()) return code;
    if (code != 0) throw voca::RuntimeFailure(fmt::format("voca {} failed with exit code {}", name, code));
    return code;
  }
  throw voca::RuntimeFailure(fmt::format("the `voca {}` command is not built into this binary", name));
}

// The settings a step ran with, kept beside the demo's output (one value a line): --reuse takes what is
// there, and the summary must describe that, not the new command line.
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

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int runDemo(const DemoOptions& o) {
  // Checked before the folder is made (synth and encode would check them only after).
  if (o.seconds < 2.0 || o.seconds > 120.0) throw voca::InputError("--seconds: expected 2 to 120");
  if (o.threads < 1) throw voca::InputError(fmt::format("--threads {}: expected 1 or more", o.threads));
  voca::encode::parseBitrate(o.bitrate);
  // One server for the whole demo, from its start: a viewer connects once and sees both runs.
  const std::unique_ptr<voca::view::FoxgloveServer> view = voca::cli::startView(o.view);
  // A recording per run (both runs share their frames' stamps); checked before anything is made.
  const std::string voca_mode(voca::priorModeName(voca::PriorMode::kMvParallelOf));
  const std::string baseline_mode(voca::priorModeName(voca::PriorMode::kNone));
  const voca::pipeline::McapRunOptions baseline_mcap = voca::cli::mcapRunOptions(o.view, baseline_mode);
  const voca::pipeline::McapRunOptions voca_mcap = voca::cli::mcapRunOptions(o.view, voca_mode);
  // Ctrl-C in any step ends the demo the clean way (the steps stop at a frame boundary).
  voca::platform::installStopHandlers();
  const auto start = std::chrono::steady_clock::now();
  const fs::path out = o.out;
  const fs::path raw = out / "synth";
  const fs::path video = out / "video";
  fs::create_directories(out);

  const bool have_raw = fs::exists(raw / "calib.json");
  const fs::path render_file = out / "synth.settings", encode_file = out / "video.settings";
  // motion, seconds; bitrate: as asked, or as the reused sequences were made (empty when unknown).
  std::vector<std::string> rendered = {o.motion, fmt::format("{}", o.seconds)}, encoded = {o.bitrate};
  const auto reused = [&](const fs::path& folder, const fs::path& file, std::vector<std::string>& used,
                          const char* options) {
    const std::vector<std::string> asked = used;
    used = readSettings(file);
    if (!used.empty() && used != asked) {
      fmt::print(stderr, "warning: --reuse: {} was made with {} {}, not as asked; drop --reuse to make it again\n",
                 folder.string(), options, fmt::join(used, " "));
    }
  };
  std::error_code ignored;
  if (!(o.reuse && have_raw)) {
    fmt::print(stderr, "[1/4] rendering {} s of fast motion with `voca synth` into {}\n", o.seconds, raw.string());
    fs::remove(render_file, ignored);
    fs::remove_all(raw, ignored);
    const int code =
        runSubcommand("synth", {"--out", raw.string(), "--motion", o.motion, "--seconds", fmt::format("{}", o.seconds),
                                "--supersample", "2", "--threads", std::to_string(o.threads)});
    if (code != 0) {
      // A stopped synth keeps a shorter sequence; --reuse must not take it for the demo's.
      fs::remove_all(raw, ignored);
      fmt::print(stderr, "voca demo: stopped; the shortened rendering {} was removed\n", raw.string());
      return code;
    }
    writeSettings(render_file, rendered);
  } else {
    fmt::print(stderr, "[1/4] reusing {}\n", raw.string());
    reused(raw, render_file, rendered, "--motion and --seconds");
  }
  if (!(o.reuse && have_raw && fs::exists(video / "mav0" / "cam1" / "data.mp4"))) {
    fmt::print(stderr, "[2/4] encoding both cameras at {} with `voca encode` into {}\n", o.bitrate, video.string());
    fs::remove(encode_file, ignored);
    const int code = runSubcommand("encode", {raw.string(), "--out", video.string(), "--bitrate", o.bitrate});
    if (code != 0) return code;
    writeSettings(encode_file, encoded);
  } else {
    fmt::print(stderr, "[2/4] reusing {}\n", video.string());
    reused(video, encode_file, encoded, "--bitrate");
  }

  fmt::print(stderr, "[3/4] running the VO on the decoded video: baseline and VOCA\n");
  struct Variant {
    voca::PriorMode mode;
    std::string label;
    voca::pipeline::VoRunResult result;
    fs::path trajectory;
  };
  std::vector<Variant> variants = {
      {voca::PriorMode::kNone, fmt::format("baseline ({})", voca::priorModeName(voca::PriorMode::kNone)), {}, {}},
      {voca::PriorMode::kMvParallelOf, fmt::format("VOCA ({})", voca_mode), {}, {}}};
  for (Variant& v : variants) {
    voca::pipeline::VoRunOptions options;
    options.input = video;
    options.mode = v.mode;
    options.progress = false;
    v.trajectory = out / fmt::format("traj_{}.txt", voca::priorModeName(v.mode));
    options.trajectory_file = v.trajectory;
    options.view.server = view.get();
    options.mcap = v.mode == voca::PriorMode::kNone ? baseline_mcap : voca_mcap;
    v.result = voca::pipeline::runVisualOdometry(options);
    if (v.result.pipeline_report.error || v.result.stop_signal != 0) {
      voca::cli::PipelineCli defaults;
      return voca::cli::reportRunEnd(v.result, defaults, "demo");
    }
    for (const std::string& warning : v.result.warnings) fmt::print(stderr, "warning: {}\n", warning);
  }

  const fs::path overlay = out / fmt::format("overlay_{}.mp4", voca_mode);
  fmt::print(stderr, "[4/4] overlay of the VOCA tracks with `voca track --overlay`\n");
  if (const int code = runSubcommand("track", {video.string(), "--mode", voca_mode, "--overlay", overlay.string()});
      code != 0) {
    return code;
  }

  const auto stageMedianMs = [](const voca::pipeline::VoRunResult& r, std::string_view stage) {
    for (const voca::pipeline::StageReport& s : r.pipeline_report.stages) {
      if (s.name == stage) return static_cast<double>(s.service.quantileNs(0.5)) * 1e-6;
    }
    return 0.0;
  };
  const auto cell = [&](const voca::pipeline::VoRunResult& r, int what) -> std::string {
    switch (what) {
      case 0:
        return r.eval ? fmt::format("{:.4f}", r.eval->ate.stats.rmse) : "-";
      case 1:
        return r.eval && r.eval->rte ? fmt::format("{:.4f}", r.eval->rte->stats.rmse) : "-";
      case 2:
        return fmt::format("{}", r.backend.resets + r.backend.lost);
      case 3:
        return fmt::format("{}", r.backend.keyframes);
      case 4:
        return fmt::format("{:.2f}", stageMedianMs(r, "frontend"));
      default:
        return fmt::format("{:.2f}", stageMedianMs(r, "backend"));
    }
  };
  const char* rows[] = {"ATE [m]",   "RTE 6 frames [m]",           "resets + lost frames",
                        "keyframes", "frontend ms/frame (median)", "backend ms/frame (median)"};
  const std::string motion =
      rendered.empty() ? fmt::format("the sequence in {}", raw.string()) : fmt::format("`{}` motion", rendered[0]);
  const std::string rate = encoded.empty() ? std::string("as found in ") + video.string() : "at " + encoded[0];
  fmt::print("\nVOCA-RT demo: {} frames of {}, stereo encoded {} per camera, decoded with motion vectors\n\n",
             variants[0].result.frames, motion, rate);
  fmt::print("{:<28} {:>18} {:>24}\n", "", variants[0].label, variants[1].label);
  for (int i = 0; i < 6; ++i) {
    fmt::print("{:<28} {:>18} {:>24}\n", rows[i], cell(variants[0].result, i), cell(variants[1].result, i));
  }
  fmt::print("\nwritten:\n");
  for (const Variant& v : variants) fmt::print("  trajectory ({}): {}\n", v.label, v.trajectory.string());
  if (!variants[0].result.ground_truth.empty()) fmt::print("  ground truth: {}\n", variants[0].result.ground_truth);
  fmt::print("  overlay video (blue previous, yellow MV prior, green tracked): {}\n", overlay.string());
  if (!voca_mcap.file.empty()) {
    fmt::print("  recordings (open in Foxglove or Lichtblick): {}, {}\n", baseline_mcap.file.string(),
               voca_mcap.file.string());
  }
  fmt::print("  sequences: {} (raw), {} (video)\n", raw.string(), video.string());
  fmt::print("compare yourself: voca eval --gt {} --est {}\n", variants[0].result.ground_truth,
             variants[1].trajectory.string());
  fmt::print("total time {:.0f} s\n", secondsSince(start));
  return 0;
}

const bool demo_command_registered = voca::cli::registerCommand({
    .name = "demo",
    .summary = "Render, encode and track a fast synthetic sequence: baseline vs VOCA side by side",
    .order = 5,
    .configure = [](CLI::App& app) -> Runner {
      auto o = std::make_shared<DemoOptions>();
      app.add_option("--out,-o", o->out, "Folder for the sequences, trajectories and overlay")->capture_default_str();
      app.add_option("--seconds", o->seconds, "Length of the rendered sequence (20 fps)")->capture_default_str();
      app.add_option("--motion", o->motion, "voca synth motion preset: gentle, fast-rotation or aggressive")
          ->capture_default_str()
          ->check(CLI::IsMember({"gentle", "fast-rotation", "aggressive"}));
      app.add_option("--bitrate", o->bitrate, "Encoding bitrate per camera")->capture_default_str();
      app.add_option("--threads", o->threads, "Rendering threads")->capture_default_str();
      app.add_flag("--reuse", o->reuse, "Reuse the sequences already rendered and encoded in --out");
      voca::cli::addViewOptions(app, o->view);
      app.footer(
          "Steps: `voca synth` (ray-cast room, exact ground truth), `voca encode` (libx264, the paper's\n"
          "settings), then the full VO on the decoded video twice: `none` (Basalt's KLT from the previous\n"
          "position) and `mv_parallel_of` (VOCA: codec motion vectors and optical flow in parallel), and\n"
          "`voca track --overlay` for a video of the tracks. ATE/RTE are computed as the paper does.\n\n" +
          voca::cli::viewHelpFooter() +
          "\nThe demo keeps one server for both runs; the page starts its graphs over when the second begins.\n"
          "--mcap rec.mcap records each run to a file of its own: rec_none.mcap and rec_mv_parallel_of.mcap.");
      return [o] { return runDemo(*o); };
    },
});

}  // namespace
