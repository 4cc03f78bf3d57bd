#include "pipeline/harness/collect_results.h"

#include <algorithm>
#include <map>
#include <optional>
#include <tuple>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "formats/dataset/dataset.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/harness/run_suite.h"
#include "pipeline/harness/suite_files.h"
#include "pipeline/harness/table_format.h"
#include "voca/core/error.h"
#include "voca/eval/evaluate.h"

namespace voca::harness {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::optional<RunMetrics> metricsFromResult(const json& result) {
  if (result.value("status", "") != "ok") return RunMetrics{RunOutcome::kCrashed, 0.0, std::nullopt, 0.0};
  RunMetrics metrics;
  metrics.ate_m = result.at("ate_m").get<double>();
  if (!result.at("rte_m").is_null()) metrics.rte_m = result.at("rte_m").get<double>();
  metrics.reset_free_fraction = result.value("reset_free_fraction", 1.0);
  return metrics;
}

// The cell of one (sequence, bitrate, system): the median over its repeats once all have a result (an
// external system's single run stands alone); nothing while a repeat is missing.
std::optional<RunMetrics> metricsOfRepeats(const std::vector<json>& results, int repeats) {
  if (results.size() == 1 && !results.front().contains("repeat")) return metricsFromResult(results.front());
  if (results.size() < static_cast<std::size_t>(repeats)) return std::nullopt;
  std::vector<RunMetrics> metrics;
  for (const json& result : results) metrics.push_back(*metricsFromResult(result));
  return medianOfRepeats(metrics);
}

// An external system's trajectory against the sequence's ground truth, like a VOCA-RT run's result.
json evaluateExternal(const ExternalRun& external, const fs::path& dataset_dir,
                      const std::optional<fs::path>& ground_truth, int max_frames) {
  json result = {{"system", external.system},
                 {"sequence", external.sequence},
                 {"bitrate", external.bitrate},
                 {"trajectory", external.trajectory.string()}};
  try {
    if (!fs::exists(external.trajectory)) throw InputError("no trajectory (the system failed)");
    const Dataset dataset = openDataset(dataset_dir);
    const std::optional<Trajectory> gt = loadGroundTruth(dataset, ground_truth);
    if (!gt) throw InputError(fmt::format("{} has no ground truth", dataset_dir.string()));
    const Trajectory estimate = loadTrajectory(external.trajectory);
    EvalOptions options;
    std::size_t frames = dataset.frames.size();
    if (max_frames > 0) frames = std::min(frames, static_cast<std::size_t>(max_frames));
    options.expected_frames = frames;
    const EvalReport report = evaluateTrajectory(estimate, *gt, options);
    result["status"] = "ok";
    result["ate_m"] = report.ate.stats.rmse;
    result["rte_m"] = report.rte ? json(report.rte->stats.rmse) : json();
    // Another system's resets are not visible in its trajectory; its gaps are.
    result["reset_free_fraction"] = std::min(1.0, report.coverage.value_or(1.0));
    result["ground_truth"] = ground_truth ? ground_truth->string() : dataset.ground_truth->string();
  } catch (const std::runtime_error& e) {  // InputError from the files, RuntimeFailure from reading them
    result["status"] = "failed";
    result["reason"] = e.what();
  }
  return result;
}

std::string csvField(const json& value) {
  if (value.is_null()) return "";
  if (value.is_string()) {
    std::string text = value.get<std::string>();
    if (text.find_first_of(",\"\n") == std::string::npos) return text;
    std::string quoted = "\"";
    for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
    return quoted + "\"";
  }
  if (value.is_boolean()) return value.get<bool>() ? "1" : "0";
  return value.dump();
}

// Issue 18's bar: a prior mode should never be more than this much worse than `none`.
constexpr double kAgainstNoneTolerance = 0.05;

// Rows of the summary's "against none" table and CSV for one bitrate: every VOCA-RT system of a prior
// mode against the `none` system of the same column config (bridging aside). External systems are left out.
void appendAgainstNone(const ResultsTable& table, const std::vector<TableSystem>& systems, const SuitePlan& plan,
                       const std::string& bitrate, std::string& md, std::string& csv) {
  const auto planned = [&](const std::string& system) -> const PlannedRun* {
    const auto it = std::find_if(plan.runs.begin(), plan.runs.end(),
                                 [&](const PlannedRun& r) { return r.system == system && r.bitrate == bitrate; });
    return it == plan.runs.end() ? nullptr : &*it;
  };
  for (std::size_t s = 0; s < systems.size(); ++s) {
    const PlannedRun* run = planned(systems[s].name);
    if (run == nullptr || run->mode == "none") continue;
    std::size_t baseline = systems.size();
    for (std::size_t b = 0; b < systems.size(); ++b) {
      const PlannedRun* candidate = planned(systems[b].name);
      if (candidate != nullptr && candidate->mode == "none" && candidate->suite_config == run->suite_config) {
        baseline = b;
      }
    }
    if (baseline == systems.size()) continue;
    const auto percent = [](double change) { return fmt::format("{:+.1f} %", 100.0 * change); };
    std::string row = fmt::format("| {} | {} |", bitrate, systems[s].name);
    std::size_t failed = 0;
    for (const TableMetric metric : {TableMetric::kRte, TableMetric::kAte}) {
      const BaselineComparison c = compareWithBaseline(table, s, baseline, metric, kAgainstNoneTolerance);
      failed = std::max(failed, c.failed_only_system);
      if (metric == TableMetric::kRte) row += fmt::format(" {} |", c.compared);
      if (c.compared == 0) {
        row += " – | – | – |";
      } else {
        row += fmt::format(" {} | {} ({}) | {} |", percent(c.mean_change), percent(c.worst_change),
                           table.sequences[c.worst_sequence], c.worse_than_tolerance);
      }
      csv += fmt::format("{},{},{},{},{},{:.6g},{:.6g},{},{},{},{}\n", csvField(bitrate), csvField(systems[s].name),
                         csvField(systems[baseline].name), metric == TableMetric::kRte ? "rte" : "ate", c.compared,
                         c.mean_change, c.worst_change,
                         c.compared == 0 ? std::string() : csvField(table.sequences[c.worst_sequence]),
                         c.worse_than_tolerance, c.failed_only_system, c.failed_only_baseline);
    }
    md += row + fmt::format(" {} |\n", failed);
  }
}

}  // namespace

std::vector<fs::path> collectResults(const fs::path& out, const std::string& voca_executable) {
  const std::optional<json> suite_json = readJson(out / "suite.json");
  if (!suite_json) {
    throw InputError(
        fmt::format("{}: no suite.json (made by `voca bench suite ... --out {}`)", out.string(), out.string()));
  }
  const Suite suite = parseSuite(*suite_json, out, (out / "suite.json").string());
  const SuitePlan plan = planSuite(suite, out, voca_executable);

  // Results by (sequence, bitrate, system), one per repeat.
  std::map<std::tuple<std::string, std::string, std::string>, std::vector<json>> results;
  std::vector<json> rows;
  for (const PlannedRun& run : plan.runs) {
    std::optional<json> result = readJson(resultFile(run.job.output));
    if (!result && (fs::exists(statisticsFile(run.job.output)) || fs::exists(trajectoryFile(run.job.output)))) {
      // A cluster job leaves outputs but no result.json: summarise it now (its exit code is unknown). Only a
      // finished run is stored as done; one without statistics may still be running elsewhere.
      result = summariseRun(run, std::nullopt, 0.0);
      if (result->value("status", "") == "ok") writeFile(resultFile(run.job.output), result->dump(2) + "\n");
    }
    if (!result) continue;
    (*result)["repeat"] = run.repeat;
    results[{run.sequence, run.bitrate, run.system}].push_back(*result);
    rows.push_back(*result);
  }
  for (const ExternalRun& external : suite.external) {
    const auto sequence = std::find_if(suite.sequences.begin(), suite.sequences.end(),
                                       [&](const SuiteSequence& s) { return s.name == external.sequence; });
    const fs::path dataset = sequence->synth_args.empty() ? sequence->path : out / "sequences" / sequence->name;
    json result = evaluateExternal(external, dataset, sequence->ground_truth, suite.frames);
    if (!fs::exists(external.trajectory)) {
      // The paper's x for a system that wrote nothing; said aloud, since a mistyped path reads the same.
      fmt::print(stderr, "warning: {} on {} at {}: {} does not exist, so its cell is x (failed)\n", external.system,
                 external.sequence, external.bitrate, external.trajectory.string());
    }
    results[{external.sequence, external.bitrate, external.system}] = {result};
    rows.push_back(result);
  }

  std::vector<fs::path> written;
  std::vector<std::string> sequences;
  std::vector<TableRules> rules;
  std::string own_rules;  // the table note naming the sequences with bounds of their own
  for (const SuiteSequence& s : suite.sequences) {
    sequences.push_back(s.name);
    rules.push_back(s.rules.value_or(suite.rules));
    if (s.rules) {
      own_rules += fmt::format("{}{} (ATE > {:g} m, RTE > {:g} cm, R at {:.0f}%)", own_rules.empty() ? "" : "; ",
                               s.name, s.rules->ate_divergence_m, 100.0 * s.rules->rte_divergence_m,
                               100.0 * s.rules->min_reset_free_fraction);
    }
  }
  if (!own_rules.empty()) own_rules = "Sequences with bounds of their own: " + own_rules + ".\n";
  std::string summary_md = fmt::format("# {}: summary\n\n", suite.name);
  std::string starts;  // "0, 5, 10": the frames the repeats track from
  for (int r = 0; r < suite.repeats; ++r) {
    starts += fmt::format("{}{}", r > 0 ? ", " : "", r * suite.repeat_step_frames);
  }
  if (suite.repeats > 1) {
    summary_md += fmt::format(
        "Every VOCA-RT cell is the median of {} runs tracking from frames {} (each metric on its own; "
        "results.csv lists every run, column repeat)\n\n",
        suite.repeats, starts);
  }
  std::string summary_csv = "system,bitrate,sequences,med_ate_m,med_rte_m,avg_ate_m,avg_rte_m,sr_ate,sr_rte\n";
  const auto number = [](const TableCell& cell) {
    return cell.kind == CellKind::kValue ? fmt::format("{:.9g}", cell.value) : std::string();
  };
  std::string against_none_md, against_none_csv;
  std::map<std::string, std::map<std::string, std::string>> pivot;  // system -> bitrate -> "MED ATE / SR"
  for (const std::string& bitrate : suite.bitrates) {
    std::vector<TableSystem> systems;
    for (const std::string& system : plan.systems) {
      const bool present =
          std::any_of(plan.runs.begin(), plan.runs.end(),
                      [&](const PlannedRun& r) { return r.bitrate == bitrate && r.system == system; }) ||
          std::any_of(suite.external.begin(), suite.external.end(),
                      [&](const ExternalRun& e) { return e.bitrate == bitrate && e.system == system; });
      if (present) systems.push_back({system});
    }
    std::vector<std::vector<std::optional<RunMetrics>>> runs;
    for (const std::string& sequence : sequences) {
      auto& row = runs.emplace_back();
      for (const TableSystem& system : systems) {
        const auto it = results.find({sequence, bitrate, system.name});
        row.push_back(it == results.end() ? std::nullopt : metricsOfRepeats(it->second, suite.repeats));
      }
    }
    const ResultsTable table = buildResultsTable(systems, sequences, runs, rules);
    std::string title = bitrate == "raw" ? "raw images" : fmt::format("{}bit/s per camera", bitrate);
    if (suite.repeats > 1) title += fmt::format(", median of {} runs from frames {}", suite.repeats, starts);
    const fs::path base = out / "tables" / bitrate;
    writeFile(base.string() + ".md",
              tableMarkdown(table, fmt::format("{}: {}", suite.name, title), suite.rules) + own_rules);
    writeFile(base.string() + ".csv", tableCsv(table));
    writeFile(base.string() + ".tex", tableLatex(table, fmt::format("{}, {}.", suite.name, title), suite.rules));
    for (const char* ext : {".md", ".csv", ".tex"}) written.push_back(base.string() + ext);
    appendAgainstNone(table, systems, plan, bitrate, against_none_md, against_none_csv);
    for (std::size_t s = 0; s < systems.size(); ++s) {
      summary_csv += fmt::format("\"{}\",{},{},{},{},{},{},{:.6g},{:.6g}\n", systems[s].name, bitrate, sequences.size(),
                                 number(table.median[0][s]), number(table.median[1][s]), number(table.average[0][s]),
                                 number(table.average[1][s]), table.success_rate[0][s], table.success_rate[1][s]);
      pivot[systems[s].name][bitrate] = fmt::format(
          "{} / {} / {:.0f}%", cellText(table.median[0][s], TableMetric::kAte, TextStyle::kPlain),
          cellText(table.median[1][s], TableMetric::kRte, TextStyle::kPlain), 100.0 * table.success_rate[0][s]);
    }
  }
  summary_md += "MED ATE [cm] / MED RTE [cm] / ATE success rate, per system and bitrate\n\n| system |";
  for (const std::string& bitrate : suite.bitrates) summary_md += " " + bitrate + " |";
  summary_md += "\n|---|";
  for (std::size_t i = 0; i < suite.bitrates.size(); ++i) summary_md += "---:|";
  summary_md += "\n";
  for (const std::string& system : plan.systems) {
    summary_md += "| " + system + " |";
    for (const std::string& bitrate : suite.bitrates) {
      const auto it = pivot[system].find(bitrate);
      summary_md += fmt::format(" {} |", it == pivot[system].end() ? std::string() : it->second);
    }
    summary_md += "\n";
  }
  if (!against_none_md.empty()) {
    summary_md += fmt::format(
        "\nPrior modes against `none` with the same config: per-sequence change of the error over the sequences "
        "both completed (negative = lower than `none`'s), its mean and worst, the sequences more than {:.0f} % "
        "worse, and those only the mode failed (divergence, crash or reset)\n\n"
        "| bitrate | system | sequences | RTE mean | RTE worst | RTE > {:.0f} % | ATE mean | ATE worst "
        "| ATE > {:.0f} % | failed |\n|---|---|---:|---:|---|---:|---:|---|---:|---:|\n",
        100.0 * kAgainstNoneTolerance, 100.0 * kAgainstNoneTolerance, 100.0 * kAgainstNoneTolerance);
    summary_md += against_none_md;
  }
  // Encoded size per sequence and bitrate: what the bitrate buys.
  summary_md += "\nEncoded video (both cameras) per sequence, bytes\n\n| sequence |";
  for (const std::string& bitrate : suite.bitrates) {
    if (bitrate != "raw") summary_md += " " + bitrate + " |";
  }
  summary_md += "\n|---|";
  for (const std::string& bitrate : suite.bitrates) {
    if (bitrate != "raw") summary_md += "---:|";
  }
  summary_md += "\n";
  for (const SuiteSequence& sequence : suite.sequences) {
    summary_md += "| " + sequence.name + " |";
    for (const std::string& bitrate : suite.bitrates) {
      if (bitrate == "raw") continue;
      const auto run = std::find_if(plan.runs.begin(), plan.runs.end(), [&](const PlannedRun& r) {
        return r.sequence == sequence.name && r.bitrate == bitrate;
      });
      const std::int64_t bytes = run == plan.runs.end() ? 0 : videoBytes(run->input);
      summary_md += bytes > 0 ? fmt::format(" {} |", bytes) : std::string(" ? |");
    }
    summary_md += "\n";
  }
  writeFile(out / "summary.md", summary_md);
  writeFile(out / "summary.csv", summary_csv);
  written.push_back(out / "summary.md");
  written.push_back(out / "summary.csv");
  if (!against_none_csv.empty()) {
    writeFile(out / "against_none.csv",
              "bitrate,system,baseline,metric,compared,mean_change,worst_change,worst_sequence,worse_than_5pct,"
              "failed_only_system,failed_only_baseline\n" +
                  against_none_csv);
    written.push_back(out / "against_none.csv");
  }

  const std::vector<std::string> columns = {"id",         "system",     "sequence",     "bitrate",
                                            "mode",       "repeat",     "bridge",       "config",
                                            "status",     "ate_m",      "rte_m",        "reset_free_fraction",
                                            "resets",     "frames",     "video_bytes",  "wall_s",
                                            "statistics", "trajectory", "ground_truth", "reason"};
  std::string csv;
  for (const std::string& column : columns) csv += fmt::format("{}{}", csv.empty() ? "" : ",", column);
  csv += "\n";
  for (const json& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c > 0) line += ',';
      line += csvField(row.contains(columns[c]) ? row.at(columns[c]) : json());
    }
    csv += line + "\n";
  }
  writeFile(out / "results.csv", csv);
  written.push_back(out / "results.csv");
  return written;
}

}  // namespace voca::harness
