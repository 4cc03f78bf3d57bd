// `voca synth`: renders a synthetic stereo sequence with exact ground truth into a EuRoC folder.

#include <fmt/core.h>

#include <memory>

#include "pipeline/synth/synth_runner.h"
#include "platform/realtime/stop_signal.h"
#include "tools/voca/command.h"

namespace {

int runSynth(voca::pipeline::SynthOptions options) {
  // A signal ends the rendering after the current frame; the frames so far are kept as a sequence.
  voca::platform::installStopHandlers();
  options.stop_requested = voca::platform::stopRequested;
  const voca::pipeline::SynthResult result = voca::pipeline::synthesizeSequence(options);
  for (const std::string& warning : result.warnings) fmt::print(stderr, "voca synth: warning: {}\n", warning);
  if (result.stopped) {
    fmt::print(stderr,
               "voca synth: stopped by a signal after {} of {} stereo frames: {} holds those {} as a complete, "
               "shorter sequence (ground truth, calib.json){}\n",
               result.frames, result.planned_frames, options.out.string(), result.frames,
               result.frames < 2 ? "; too short to run" : "");
    return voca::platform::interruptedExitCode(voca::platform::stopSignal());
  }
  fmt::print(stderr, "voca synth: wrote {} ({} stereo frames, ground truth, calib.json) in {:.1f} s\n",
             options.out.string(), result.frames, result.seconds);
  if (result.motion.samples == 0) {
    fmt::print(stderr,
               "voca synth: cam0 image motion per frame: not measurable, no scene point stays in view from one "
               "frame to the next (the motion is too fast for this frame rate)\n");
  } else {
    fmt::print(stderr, "voca synth: cam0 image motion per frame: median {:.1f} px, p90 {:.1f} px, max {:.1f} px\n",
               result.motion.median_px, result.motion.p90_px, result.motion.max_px);
  }
  if (result.blur_median_px) {
    fmt::print(stderr, "voca synth: cam0 motion blur streak ({} ms exposure): median {:.1f} px, max {:.1f} px\n",
               options.exposure_ms, *result.blur_median_px, *result.blur_max_px);
  }
  return 0;
}

const bool synth_command_registered = voca::cli::registerCommand(
    {.name = "synth",
     .summary = "Render a synthetic stereo sequence with exact ground truth (EuRoC folder + calib.json)",
     .order = 10,
     .configure = [](CLI::App& app) -> voca::cli::Runner {
       auto options = std::make_shared<voca::pipeline::SynthOptions>();
       app.description(
           "Ray-casts a textured room with objects through a real camera model and writes a EuRoC folder\n"
           "(mav0/cam0, mav0/cam1), ground truth of the body frame at every frame\n"
           "(mav0/state_groundtruth_estimate0/data.csv) and the rig as Basalt JSON (<out>/calib.json).\n"
           "The output is deterministic: the same options give the same bytes.");
       app.add_option("--out,-o", options->out, "Output folder (created)")->required();
       app.add_option("--camera", options->camera,
                      "euroc (pinhole-radtan 752x480), tumvi (kb4 512x512) or a calibration file/folder")
           ->capture_default_str();
       CLI::Option* trajectory =
           app.add_option("--trajectory", options->trajectory,
                          "Follow this trajectory (TUM, EuRoC csv) instead of a preset; resampled to --rate and "
                          "re-centred in the room (its z axis is taken as up)");
       app.add_option("--motion", options->motion, "Motion preset: gentle, fast-rotation or aggressive")
           ->capture_default_str()
           ->excludes(trajectory);
       app.add_option("--seconds", options->seconds, "Duration (default: 20 s for presets, the whole trajectory file)");
       app.add_option("--start", options->start_s,
                      "With --trajectory: skip this many seconds of it first (e.g. a take-off or a standstill)")
           ->capture_default_str();
       app.add_option("--rate", options->rate_hz, "Frame rate, Hz")->capture_default_str();
       app.add_option("--seed", options->seed, "Seed of the sensor noise")->capture_default_str();
       app.add_option("--scene-seed", options->scene_seed, "Seed of the room's layout and textures")
           ->capture_default_str();
       app.add_option("--psf-sigma", options->psf_sigma_px,
                      "Lens blur: Gaussian point spread, sigma in px (0 = none; ~0.6 is a typical real lens)")
           ->capture_default_str();
       app.add_option("--noise-sigma", options->noise_sigma, "Gaussian sensor noise, gray levels")
           ->capture_default_str();
       app.add_option("--supersample", options->supersample, "n x n samples in pixels crossed by an edge (1..8)")
           ->capture_default_str();
       app.add_option("--threads", options->threads, "Rendering threads")->capture_default_str();
       app.add_option("--exposure", options->exposure_ms,
                      "Motion blur: shutter open for this many ms, centred on each timestamp (0 = instantaneous; "
                      "EuRoC's cameras expose up to ~10 ms in dim halls)")
           ->capture_default_str();
       app.add_option("--gain", options->gain,
                      "Sensor gain on the scene's brightness before noise: < 1 renders a dark, low-contrast scene "
                      "(e.g. 0.25), where the same noise weighs 4x more")
           ->capture_default_str();
       return [options] { return runSynth(*options); };
     }});

}  // namespace
