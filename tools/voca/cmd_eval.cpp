// `voca eval`: ATE and RTE of an estimated trajectory against ground truth, as the paper reports them.

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "formats/eval/eval_inputs.h"
#include "formats/eval/eval_report_json.h"
#include "formats/trajectory/trajectory_io.h"
#include "platform/filesystem/output_paths.h"
#include "tools/voca/command.h"
#include "tools/voca/number_checks.h"
#include "voca/core/error.h"
#include "voca/eval/evaluate.h"

namespace {

// Command-line settings of `voca eval`.
struct EvalCommandOptions {
  std::string gt_path, est_path;
  std::string gt_format = "auto", est_format = "auto";
  std::string gt_times, est_times;
  std::string gt_frame = "auto", est_frame = "auto";
  std::string calib_path;
  double delta = 6.0;
  std::string delta_unit = "frames";
  double max_diff_s = 0.01;
  std::string align = "se3";
  double ate_divergence_m = 10.0;
  double rte_divergence_m = 0.10;
  std::optional<std::size_t> expected_frames;
  std::string json_path;
};

// A trajectory file as given on the command line, with what was decided about it.
using LoadedTrajectory = voca::EvalInput;

std::string verdictText(voca::EvalVerdict verdict, bool available, double threshold_m,
                        const std::optional<double>& coverage) {
  if (!available) return "n/a";
  switch (verdict) {
    case voca::EvalVerdict::kOk:
      return "ok";
    case voca::EvalVerdict::kDivergent:
      return fmt::format("divergent (rmse > {} m)", threshold_m);
    case voca::EvalVerdict::kReset:
      return fmt::format("R (only {:.0f} % of the frames estimated)", 100.0 * coverage.value_or(0.0));
  }
  return "";
}

void printReport(const voca::EvalReport& report, const voca::EvalOptions& options, const LoadedTrajectory& est,
                 const LoadedTrajectory& gt, const EvalCommandOptions& cli) {
  fmt::print("estimate:     {} ({}, {} poses, {} frame)\n", cli.est_path, voca::trajectoryFormatName(est.format),
             report.est_poses, est.frame);
  fmt::print("ground truth: {} ({}, {} poses, {} frame)\n", cli.gt_path, voca::trajectoryFormatName(gt.format),
             report.gt_poses, gt.frame);
  const voca::PoseAssociation& a = report.association;
  if (a.by_index) {
    fmt::print("association:  by index (no timestamps), {} pairs\n", a.size());
  } else {
    fmt::print(
        "association:  by timestamp within {} s: {} pairs of {} estimated poses, |dt| mean {:.3g} s, max {:.3g} s{}\n",
        a.max_diff_s, a.size(), report.est_poses, a.mean_abs_dt_s, a.max_abs_dt_s,
        a.reused_poses ? fmt::format(", {} poses paired twice or more", a.reused_poses) : "");
  }
  if (report.coverage) {
    fmt::print("coverage:     {} of {} expected frames ({:.1f} %)\n", report.est_poses, *options.expected_frames,
               100.0 * *report.coverage);
  }
  fmt::print("\n{:<26} {:>10} {:>10} {:>10} {:>10} {:>7}  {}\n", "metric [m]", "rmse", "mean", "median", "max", "count",
             "verdict");
  const std::string ate_name = fmt::format("ATE ({} aligned)", voca::alignModeName(options.align));
  const voca::ErrorStats& ate = report.ate.stats;
  fmt::print("{:<26} {:>10.6f} {:>10.6f} {:>10.6f} {:>10.6f} {:>7}  {}\n", ate_name, ate.rmse, ate.mean, ate.median,
             ate.max, ate.count, verdictText(report.ate_verdict, true, options.ate_divergence_m, report.coverage));
  const std::string rte_name =
      fmt::format("RTE (delta {} {})", options.rte_delta, voca::deltaUnitName(options.rte_delta_unit));
  if (report.rte) {
    const voca::ErrorStats& rte = report.rte->stats;
    fmt::print("{:<26} {:>10.6f} {:>10.6f} {:>10.6f} {:>10.6f} {:>7}  {}\n", rte_name, rte.rmse, rte.mean, rte.median,
               rte.max, rte.count, verdictText(report.rte_verdict, true, options.rte_divergence_m, report.coverage));
  } else {
    fmt::print("{:<26} {:>10} {:>10} {:>10} {:>10} {:>7}  too few associated poses for one pair\n", rte_name, "-", "-",
               "-", "-", 0);
  }
  if (options.align != voca::AlignMode::kNone && report.ate.alignment.scale != 1.0) {
    fmt::print("alignment scale: {:.6f}\n", report.ate.alignment.scale);
  }
}

int runEval(const EvalCommandOptions& cli) {
  const voca::NamedPath report_file{"--json", cli.json_path};
  const voca::NamedPath inputs[] = {{"--gt", cli.gt_path},
                                    {"--est", cli.est_path},
                                    {"--gt-times", cli.gt_times},
                                    {"--est-times", cli.est_times},
                                    {"--calib", cli.calib_path}};
  // Missing inputs are bad input (exit code 1), named like the other commands' (CLI11's check exited 2).
  for (const voca::NamedPath& input : inputs) {
    if (input.path.empty()) continue;
    std::error_code error;
    const bool folder_allowed = input.what == "--calib";  // a dataset folder holds its calibration
    if (!std::filesystem::exists(input.path, error)) {
      throw voca::InputError(fmt::format("{} {}: no such file", input.what, input.path.string()));
    }
    if (!folder_allowed && std::filesystem::is_directory(input.path, error)) {
      throw voca::InputError(fmt::format("{} {}: a folder, not a file", input.what, input.path.string()));
    }
  }
  voca::requireOutputsApart({&report_file, 1}, inputs);
  voca::requireWritableFile(report_file);  // before the evaluation, not after its report is printed
  LoadedTrajectory gt = voca::loadEvalInput(cli.gt_path, cli.gt_format, cli.gt_times, cli.gt_frame);
  LoadedTrajectory est = voca::loadEvalInput(cli.est_path, cli.est_format, cli.est_times, cli.est_frame);
  voca::matchPoseFrames(est, gt, cli.calib_path);

  voca::EvalOptions options;
  options.max_diff_s = cli.max_diff_s;
  options.align = cli.align == "none"   ? voca::AlignMode::kNone
                  : cli.align == "sim3" ? voca::AlignMode::kSim3
                                        : voca::AlignMode::kSe3;
  options.rte_delta = cli.delta;
  options.rte_delta_unit = cli.delta_unit == "m" ? voca::DeltaUnit::kMeters : voca::DeltaUnit::kFrames;
  options.ate_divergence_m = cli.ate_divergence_m;
  options.rte_divergence_m = cli.rte_divergence_m;
  options.expected_frames = cli.expected_frames;

  const voca::EvalReport report = voca::evaluateTrajectory(est.trajectory, gt.trajectory, options);
  printReport(report, options, est, gt, cli);

  if (!cli.json_path.empty()) {
    nlohmann::json j = voca::evalReportToJson(report, options);
    j["estimate"] = {{"path", cli.est_path}, {"format", voca::trajectoryFormatName(est.format)}, {"frame", est.frame}};
    j["ground_truth"] = {{"path", cli.gt_path}, {"format", voca::trajectoryFormatName(gt.format)}, {"frame", gt.frame}};
    if (!cli.calib_path.empty()) j["calibration"] = cli.calib_path;
    std::ofstream out(cli.json_path);
    out << j.dump(2) << '\n';
    out.close();  // a full disk shows only when the buffer is written out
    if (!out) throw voca::InputError(fmt::format("cannot write {}: {}", cli.json_path, std::strerror(errno)));
  }
  return 0;
}

const bool eval_command_registered = voca::cli::registerCommand(
    {.name = "eval",
     .summary = "ATE and RTE of an estimated trajectory against ground truth (evo-compatible)",
     .order = 60,
     .configure = [](CLI::App& app) -> voca::cli::Runner {
       auto o = std::make_shared<EvalCommandOptions>();
       app.description(
           "Compares an estimated trajectory with ground truth as the VOCA paper does (and as evo computes it):\n"
           "  ATE: poses associated by timestamp, aligned with SE(3) Umeyama, RMSE of the position errors\n"
           "       (evo_ape -a).\n"
           "  RTE: translation error of relative poses between frames i and i+delta, consecutive pairs, no\n"
           "       alignment (evo_rpe -d 6 -u f).\n"
           "A run is divergent when ATE > 10 m or RTE > 0.10 m (use --ate-divergence 1 for the Monado dataset), and\n"
           "R when fewer than half of --expected-frames were estimated.\n"
           "Formats are detected: TUM (t tx ty tz qx qy qz qw, seconds), EuRoC csv (t_ns,p,q as w x y z), KITTI\n"
           "(3x4 rows; timestamps from --gt-times/--est-times, otherwise poses are paired by index, as evo does).\n\n"
           "Example: voca eval --gt mav0/state_groundtruth_estimate0/data.csv --est out/trajectory.txt --json r.json");
       app.add_option("--gt", o->gt_path, "Ground-truth trajectory file")->required();
       app.add_option("--est", o->est_path, "Estimated trajectory file")->required();
       app.add_option("--gt-format", o->gt_format, "Ground-truth format")
           ->check(CLI::IsMember({"auto", "tum", "euroc", "kitti"}))
           ->capture_default_str();
       app.add_option("--est-format", o->est_format, "Estimate format")
           ->check(CLI::IsMember({"auto", "tum", "euroc", "kitti"}))
           ->capture_default_str();
       app.add_option("--gt-times", o->gt_times, "Times file (seconds per line) for a KITTI ground truth");
       app.add_option("--est-times", o->est_times, "Times file (seconds per line) for a KITTI estimate");
       app.add_option("--delta", o->delta, "RTE spacing of the pose pairs")->capture_default_str();
       app.add_option("--delta-unit", o->delta_unit,
                      "Unit of --delta: frames (the paper), or m of travelled path as evo_rpe -u m")
           ->check(CLI::IsMember({"frames", "m"}))
           ->capture_default_str();
       app.add_option("--max-diff", o->max_diff_s, "Largest timestamp difference [s] for associating two poses")
           ->check(voca::cli::nonNegativeNumber())
           ->capture_default_str();
       app.add_option("--align", o->align, "ATE alignment: se3 (stereo, the paper), sim3 (with scale) or none")
           ->check(CLI::IsMember({"se3", "sim3", "none"}))
           ->capture_default_str();
       app.add_option("--ate-divergence", o->ate_divergence_m, "ATE RMSE [m] above which the run is divergent")
           ->check(voca::cli::positiveNumber())
           ->capture_default_str();
       app.add_option("--rte-divergence", o->rte_divergence_m, "RTE RMSE [m] above which the run is divergent")
           ->check(voca::cli::positiveNumber())
           ->capture_default_str();
       app.add_option("--expected-frames", o->expected_frames,
                      "Frames the run should have estimated; fewer than half estimated gives the verdict R")
           ->check(voca::cli::positiveNumber());
       app.add_option("--calib", o->calib_path,
                      "Calibration (Basalt json, Kalibr yaml, KITTI calib.txt or dataset folder) giving T_body_cam0, "
                      "to compare trajectories given in different frames");
       app.add_option("--est-frame", o->est_frame,
                      "Frame of the estimate's poses (auto: cam0 for KITTI files, body otherwise)")
           ->check(CLI::IsMember({"auto", "body", "cam0"}))
           ->capture_default_str();
       app.add_option("--gt-frame", o->gt_frame,
                      "Frame of the ground truth's poses (auto: cam0 for KITTI files, body otherwise)")
           ->check(CLI::IsMember({"auto", "body", "cam0"}))
           ->capture_default_str();
       app.add_option("--json", o->json_path, "Also write the full report as JSON to this file");
       return [o] { return runEval(*o); };
     }});

}  // namespace
