#pragma once
// `voca demo`, the README's main job: renders a short synthetic stereo sequence with exact ground
// truth, encodes it the way the paper did, runs the whole VO on the decoded video twice (the baseline
// tracker without priors, and VOCA: motion vectors in parallel with optical flow), and draws the VOCA
// tracks into an overlay video. With reuse, the sequences already in the folder are taken as they are.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

struct DemoOptions {
  std::filesystem::path out = "voca-demo";  // synth/, video/, the trajectories and the overlay
  double seconds = 6.0;                     // rendered length, 2 to 120 s at 20 fps
  std::string motion = "fast-rotation";     // synth motion preset
  std::string bitrate = "500k";             // per camera, as `voca encode --bitrate` reads it
  int threads = 2;                          // rendering threads
  bool reuse = false;                       // take the sequences already rendered and encoded in out
  ViewRunOptions view;                      // one server for both runs, started by the caller
  McapRunOptions baseline_mcap, voca_mcap;  // a recording per run (no file: none)
  // Asked between frames of every step; true ends the demo there.
  std::function<bool()> stop_requested;
};

// One VO run of the demo.
struct DemoRun {
  PriorMode mode = PriorMode::kNone;
  std::string label;  // "baseline (none)", "VOCA (mv_parallel_of)"
  std::filesystem::path trajectory;
  VoRunResult result;
};

struct DemoResult {
  enum class End {
    kDone,
    kStoppedRendering,  // the shortened rendering was removed: reuse cannot mistake it for the demo's
    kStoppedEncoding,   // nothing was written to the video folder
    kRunEnded,          // a VO run (or the overlay's) failed or was stopped: ended_run says which
  };
  End end = End::kDone;
  std::filesystem::path raw, video, overlay;
  // The settings the sequences were made with (motion and seconds; bitrate): as asked, or as recorded
  // beside reused sequences; empty when reused sequences carry no record.
  std::vector<std::string> rendered, encoded;
  std::vector<DemoRun> runs;  // baseline, then VOCA
  VoRunResult ended_run;      // End::kRunEnded: the run that ended the demo
  double seconds = 0.0;       // wall time
};

// InputError naming the first option out of range (seconds, threads, bitrate).
void checkDemoOptions(const DemoOptions& options);

// Checks the options (checkDemoOptions) before anything is made, then runs the steps,
// each announced on stderr ("[1/4] rendering ..."). Warnings (reused sequences made with other
// settings than asked) go to stderr as they are found.
DemoResult runDemo(const DemoOptions& options);

}  // namespace voca::pipeline
