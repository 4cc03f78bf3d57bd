#pragma once
// The one runner behind `voca run`, `voca track`, `voca demo`, `voca bench` and the library API:
// opens an input (a raw dataset, optionally encoded first the way the paper did, a VOCA video folder,
// a stream or a recording of one), runs the staged pipeline (read -> [decode] -> frontend ->
// [backend] -> write) as a VoSession and returns everything a caller prints or checks: trajectory,
// statistics, per-stage latency, drops, damaged frames, and ATE/RTE when the dataset has ground
// truth. Outputs stream while the run goes: a stopped or failed run leaves every pose estimated so
// far in the trajectory file.
//
// The parts, each in its own file: run_input (what the input is and opening it), output_checks
// (outputs apart from inputs, before any work), vo_session (the stages and sinks), run_summary (what
// the commands print), statistics_file (--stats).

#include <optional>
#include <string>

#include "pipeline/vo/run_summary.h"
#include "pipeline/vo/statistics_file.h"
#include "pipeline/vo/vo_run.h"

namespace voca::pipeline {

// Throws InputError for bad input found before the run starts (missing dataset, calibration or
// config; images that do not match the calibration). A stage failing during the run does not throw:
// the result carries it in pipeline_report.error, with everything estimated up to then. Writes
// options.statistics_file at the end.
VoRunResult runVisualOdometry(const VoRunOptions& options);

// The same on an input that is already open (a live camera, a test's source): options' input,
// calibration, config, ground_truth, encode_bitrate_bps, first_frame and max_frames are not used; its
// mode and bridge_iframes still override the config's. Does not write options.statistics_file (the
// caller does, after adding its own warnings). ground_truth, when given, is evaluated against.
VoRunResult runVisualOdometryOn(StereoSource& source, const StereoRig& rig, const VocaConfig& config,
                                const VoRunOptions& options, const std::optional<Trajectory>& ground_truth = {},
                                const std::string& ground_truth_name = {});

}  // namespace voca::pipeline
