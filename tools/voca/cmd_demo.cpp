// `voca demo`: the README's main job in one command (pipeline/demo/demo_runner.h). Renders a short
// synthetic stereo sequence with fast motion, encodes it at 500 kbit/s, runs the baseline tracker (no
// priors) and VOCA (motion vectors in parallel with optical flow) through the whole VO, and prints
// both side by side, with the trajectories and an overlay video of the tracks written beside.

#include <fmt/core.h>

#include <memory>
#include <string>
#include <string_view>

#include "pipeline/demo/demo_runner.h"
#include "platform/realtime/clock.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"
#include "tools/voca/pipeline_cli.h"
#include "tools/voca/view_cli.h"

namespace {

using voca::cli::Runner;
using voca::pipeline::DemoResult;
using voca::pipeline::VoRunResult;

struct DemoCli {
  voca::pipeline::DemoOptions demo;
  std::string out = demo.out.string();
  voca::cli::ViewCli view;
};

double stageMedianMs(const VoRunResult& r, std::string_view name) {
  const voca::pipeline::StageReport* stage = r.pipeline_report.stage(name);
  return stage != nullptr ? voca::platform::nsToMs(stage->service.quantileNs(0.5)) : 0.0;
}

// The side-by-side table and what was written.
void printSummary(const DemoResult& demo, const voca::pipeline::McapRunOptions& baseline_mcap,
                  const voca::pipeline::McapRunOptions& voca_mcap) {
  const auto cell = [](const VoRunResult& r, int what) -> std::string {
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
  const auto& baseline = demo.runs[0];
  const auto& voca = demo.runs[1];
  const std::string motion = demo.rendered.empty() ? fmt::format("the sequence in {}", demo.raw.string())
                                                   : fmt::format("`{}` motion", demo.rendered[0]);
  const std::string rate = demo.encoded.empty() ? "as found in " + demo.video.string() : "at " + demo.encoded[0];
  fmt::print("\nVOCA-RT demo: {} frames of {}, stereo encoded {} per camera, decoded with motion vectors\n\n",
             baseline.result.frames, motion, rate);
  fmt::print("{:<28} {:>18} {:>24}\n", "", baseline.label, voca.label);
  for (int i = 0; i < 6; ++i) {
    fmt::print("{:<28} {:>18} {:>24}\n", rows[i], cell(baseline.result, i), cell(voca.result, i));
  }
  fmt::print("\nwritten:\n");
  for (const auto& run : demo.runs) fmt::print("  trajectory ({}): {}\n", run.label, run.trajectory.string());
  if (!baseline.result.ground_truth.empty()) fmt::print("  ground truth: {}\n", baseline.result.ground_truth);
  fmt::print("  overlay video (blue previous, yellow MV prior, green tracked): {}\n", demo.overlay.string());
  if (!voca_mcap.file.empty()) {
    fmt::print("  recordings (open in Foxglove or Lichtblick): {}, {}\n", baseline_mcap.file.string(),
               voca_mcap.file.string());
  }
  fmt::print("  sequences: {} (raw), {} (video)\n", demo.raw.string(), demo.video.string());
  fmt::print("compare yourself: voca eval --gt {} --est {}\n", baseline.result.ground_truth, voca.trajectory.string());
  fmt::print("total time {:.0f} s\n", demo.seconds);
}

int runDemo(DemoCli& cli) {
  voca::pipeline::DemoOptions& options = cli.demo;
  options.out = cli.out;
  voca::pipeline::checkDemoOptions(options);
  // One server for the whole demo, from its start: a viewer connects once and sees both runs.
  const std::unique_ptr<voca::view::FoxgloveServer> view = voca::cli::startView(cli.view);
  options.view.server = view.get();
  // A recording per run (both runs share their frames' stamps); checked before anything is made.
  options.baseline_mcap = voca::cli::mcapRunOptions(cli.view, voca::priorModeName(voca::PriorMode::kNone));
  options.voca_mcap = voca::cli::mcapRunOptions(cli.view, voca::priorModeName(voca::PriorMode::kMvParallelOf));
  // Ctrl-C in any step ends the demo the clean way (the steps stop at a frame boundary).
  voca::platform::installStopHandlers();
  options.stop_requested = voca::platform::stopRequested;

  const DemoResult demo = voca::pipeline::runDemo(options);
  const int interrupted = voca::platform::interruptedExitCode(voca::platform::stopSignal());
  switch (demo.end) {
    case DemoResult::End::kStoppedRendering:
      fmt::print(stderr, "voca demo: stopped; the shortened rendering {} was removed\n", demo.raw.string());
      return interrupted;
    case DemoResult::End::kStoppedEncoding:
      fmt::print(stderr, "voca demo: stopped while encoding; nothing was written to {}\n", demo.video.string());
      return interrupted;
    case DemoResult::End::kRunEnded: {
      const voca::cli::PipelineCli defaults;
      return voca::cli::reportRunEnd(demo.ended_run, defaults, "demo");
    }
    case DemoResult::End::kDone:
      break;
  }
  printSummary(demo, options.baseline_mcap, options.voca_mcap);
  return 0;
}

const bool demo_command_registered = voca::cli::registerCommand({
    .name = "demo",
    .summary = "Render, encode and track a fast synthetic sequence: baseline vs VOCA side by side",
    .order = 5,
    .configure = [](CLI::App& app) -> Runner {
      auto cli = std::make_shared<DemoCli>();
      voca::pipeline::DemoOptions& o = cli->demo;
      app.add_option("--out,-o", cli->out, "Folder for the sequences, trajectories and overlay")->capture_default_str();
      app.add_option("--seconds", o.seconds, "Length of the rendered sequence (20 fps)")->capture_default_str();
      app.add_option("--motion", o.motion, "voca synth motion preset: gentle, fast-rotation or aggressive")
          ->capture_default_str()
          ->check(CLI::IsMember({"gentle", "fast-rotation", "aggressive"}));
      app.add_option("--bitrate", o.bitrate, "Encoding bitrate per camera")->capture_default_str();
      app.add_option("--threads", o.threads, "Rendering threads")->capture_default_str();
      app.add_flag("--reuse", o.reuse, "Reuse the sequences already rendered and encoded in --out");
      voca::cli::addViewOptions(app, cli->view);
      app.footer(
          "Steps: `voca synth` (ray-cast room, exact ground truth), `voca encode` (libx264, the paper's\n"
          "settings), then the full VO on the decoded video twice: `none` (Basalt's KLT from the previous\n"
          "position) and `mv_parallel_of` (VOCA: codec motion vectors and optical flow in parallel), and\n"
          "`voca track --overlay` for a video of the tracks. ATE/RTE are computed as the paper does.\n\n" +
          voca::cli::viewHelpFooter() +
          "\nThe demo keeps one server for both runs; the page starts its graphs over when the second begins.\n"
          "--mcap rec.mcap records each run to a file of its own: rec_none.mcap and rec_mv_parallel_of.mcap.");
      return [cli] { return runDemo(*cli); };
    },
});

}  // namespace
