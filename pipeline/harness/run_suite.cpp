#include "pipeline/harness/run_suite.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fstream>
#include <map>
#include <set>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "formats/dataset/dataset.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/harness/table_format.h"
#include "pipeline/vo/vo_runner.h"
#include "voca/core/error.h"
#include "voca/eval/evaluate.h"

namespace voca::harness {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

std::optional<json> readJson(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return std::nullopt;
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return std::nullopt;  // a file cut short or garbled by a crash: treated as absent
  }
}

// Written to a temporary name and renamed, so a reader never sees half a file.
void writeFile(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  const fs::path temp = file.string() + ".tmp";
  {
    std::ofstream out(temp, std::ios::trunc);
    out << text;
    if (!out.flush()) throw RuntimeFailure(fmt::format("{}: cannot write", temp.string()));
  }
  fs::rename(temp, file);
}

std::string duration(double seconds) {
  const auto s = static_cast<long>(std::lround(seconds));
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
  return fmt::format("{}m{:02}s", s / 60, s % 60);
}

std::int64_t videoBytes(const fs::path& input) {
  std::int64_t bytes = 0;
  for (const char* camera : {"cam0", "cam1"}) {
    std::error_code error;
    const auto size = fs::file_size(input / "mav0" / camera / "data.mp4", error);
    if (!error) bytes += static_cast<std::int64_t>(size);
  }
  return bytes;
}

// The last non-empty line of a log: usually the error a failed command printed. A usage error ends
// with the command-line parser's pointer to --help; the line before it is the reason.
std::string lastLogLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last, before_last;
  while (std::getline(in, line)) {
    const std::size_t cr = line.find_last_of('\r');
    if (cr != std::string::npos) line = line.substr(cr + 1);
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    before_last = std::move(last);
    last = line;
  }
  if (last.rfind("Run with --help", 0) == 0 && !before_last.empty()) return before_last;
  return last;
}

bool interruptedBySignal(const platform::ChildExit& exit) {
  return exit.signal == SIGINT || exit.signal == SIGTERM || exit.exit_code == 130 || exit.exit_code == 143;
}

// Up to `jobs` children at a time; `finished` is called as each ends, in the order they end.
struct RunningJob {
  std::size_t index;
  Clock::time_point start;
};

void executeJobs(std::size_t count, int jobs, const std::function<bool()>& stop_requested,
                 const std::function<std::optional<pid_t>(std::size_t)>& start,
                 const std::function<void(std::size_t, const platform::ChildExit&, double)>& finished) {
  std::map<pid_t, RunningJob> running;
  std::size_t next = 0;
  const auto stopping = [&] { return stop_requested && stop_requested(); };
  while (next < count || !running.empty()) {
    while (next < count && static_cast<int>(running.size()) < std::max(1, jobs) && !stopping()) {
      const std::size_t index = next++;
      if (const std::optional<pid_t> pid = start(index)) running[*pid] = {index, Clock::now()};
    }
    if (running.empty()) {
      if (stopping()) return;
      continue;
    }
    const platform::ChildExit exit = platform::waitForAnyChild();
    const auto it = running.find(exit.pid);
    if (it == running.end()) continue;
    const RunningJob job = it->second;
    running.erase(it);
    finished(job.index, exit, std::chrono::duration<double>(Clock::now() - job.start).count());
  }
}

std::string logName(const std::string& id) {
  std::string name = id;
  std::replace(name.begin(), name.end(), '/', '_');
  return name + ".txt";
}

// Renderings or encodings: each into <output>.partial, renamed when it succeeded, so a folder that
// exists is complete and is never made again.
std::set<std::string> prepare(const std::vector<Job>& all, const fs::path& out, const SuiteRunOptions& options,
                              const char* what, SuiteRunReport& report) {
  std::set<std::string> failed;
  std::vector<const Job*> todo;
  for (const Job& job : all) {
    if (!fs::is_directory(job.output)) todo.push_back(&job);
  }
  if (todo.empty()) return failed;
  if (options.progress) fmt::print(stderr, "{}: {} of {} to make\n", what, todo.size(), all.size());
  fs::create_directories(out / "logs");
  executeJobs(
      todo.size(), options.jobs, options.stop_requested,
      [&](std::size_t i) -> std::optional<pid_t> {
        const Job& job = *todo[i];
        const fs::path partial = job.output.string() + ".partial";
        fs::remove_all(partial);
        fs::create_directories(partial.parent_path());
        std::vector<std::string> argv = job.argv;
        std::replace(argv.begin(), argv.end(), job.output.string(), partial.string());
        const fs::path log = out / "logs" / logName(job.id);
        fs::remove(log);
        return platform::startChild(argv, log);
      },
      [&](std::size_t i, const platform::ChildExit& exit, double seconds) {
        const Job& job = *todo[i];
        const fs::path partial = job.output.string() + ".partial";
        if (options.stop_requested && options.stop_requested() && interruptedBySignal(exit))
          return;  // redone next call
        if (exit.succeeded()) {
          fs::rename(partial, job.output);
        } else {
          failed.insert(job.id);
          ++report.preparation_failures;
        }
        if (options.progress) {
          fmt::print(stderr, "  {}: {} ({:.1f} s){}\n", job.id,
                     exit.succeeded() ? "done" : platform::describeExit(exit), seconds,
                     exit.succeeded() ? "" : fmt::format(": {}", lastLogLine(out / "logs" / logName(job.id))));
        }
      });
  return failed;
}

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

double resetFreeFraction(const json& statistics) {
  const json& rows = statistics.at("frame_columns");
  const auto column = [&](const std::string& name) -> std::size_t {
    const auto it = std::find(rows.begin(), rows.end(), name);
    if (it == rows.end()) throw InputError(fmt::format("statistics without a {} column", name));
    return static_cast<std::size_t>(it - rows.begin());
  };
  const std::size_t state = column("state"), missing = column("missing_before");
  const json& frames = statistics.at("frame_rows");
  if (frames.empty()) return 0.0;
  std::size_t longest = 0, current = 0, total = 0;
  for (const json& frame : frames) {
    const auto gap = frame.at(missing).get<std::size_t>();
    total += gap + 1;
    if (gap > 0) current = 0;
    if (frame.at(state).get<std::string>() == "tracking") {
      longest = std::max(longest, ++current);
    } else {
      current = 0;
    }
  }
  return static_cast<double>(longest) / static_cast<double>(total);
}

json summariseRun(const PlannedRun& run, const std::optional<platform::ChildExit>& exit, double wall_s) {
  json result = {{"id", run.job.id},
                 {"sequence", run.sequence},
                 {"bitrate", run.bitrate},
                 {"mode", run.mode},
                 {"bridge", run.bridge},
                 {"config", run.config},
                 {"system", run.system},
                 {"input", run.input.string()},
                 {"trajectory", trajectoryFile(run.job.output).string()},
                 {"statistics", statisticsFile(run.job.output).string()},
                 {"command", shellCommand(run.job.argv)}};
  if (wall_s > 0) result["wall_s"] = wall_s;
  if (exit) {
    result["exit_code"] = exit->signal ? json() : json(exit->exit_code);
    result["signal"] = exit->signal;
  }
  if (run.bitrate != "raw") result["video_bytes"] = videoBytes(run.input);
  const auto failed = [&](const std::string& reason) {
    result["status"] = "failed";
    result["reason"] = reason;
    return result;
  };
  const std::optional<json> stats = readJson(statisticsFile(run.job.output));
  if (exit && !exit->succeeded()) {
    std::string reason = platform::describeExit(*exit);
    const std::string last = lastLogLine(logFile(run.job.output));
    if (!last.empty()) reason += ": " + last;
    if (stats) result["frames"] = stats->value("frames", 0);
    return failed(reason);
  }
  if (!stats) return failed("no statistics written (crashed before the end)");
  result["frames"] = stats->value("frames", 0);
  result["resets"] = stats->at("backend").value("resets", 0);
  result["ground_truth"] = stats->value("ground_truth", "");
  if (stats->contains("error")) return failed("stage failed: " + stats->at("error").value("message", ""));
  if (stats->value("stopped_by_signal", 0) != 0) return failed("stopped by a signal");
  if (!stats->contains("eval")) return failed("not evaluated (no ground truth, or no pose estimated)");
  const json& eval = stats->at("eval");
  result["status"] = "ok";
  result["ate_m"] = eval.at("ate").at("rmse");
  result["rte_m"] = eval.at("rte").value("available", false) ? eval.at("rte").at("rmse") : json();
  result["coverage"] = eval.value("coverage", json());
  double fraction = resetFreeFraction(*stats);
  if (eval.contains("coverage") && eval.at("coverage").is_number()) {
    fraction = std::min(fraction, eval.at("coverage").get<double>());
  }
  result["reset_free_fraction"] = fraction;
  return result;
}

void writeSuiteFile(const Suite& suite, const fs::path& out) {
  writeFile(out / "suite.json", suiteToJson(suite).dump(2) + "\n");
}

SuiteRunReport runSuite(const Suite& suite, const SuitePlan& plan, const fs::path& out,
                        const SuiteRunOptions& options) {
  SuiteRunReport report;
  report.total = static_cast<int>(plan.runs.size());
  writeSuiteFile(suite, out);
  for (const std::string& note : suite.notes) fmt::print(stderr, "note: {}\n", note);

  std::set<std::string> failed_preparations = prepare(plan.synth, out, options, "synthetic sequences", report);
  // An encoding whose rendering failed cannot start; its runs fail with the rendering's reason.
  std::vector<Job> encodes;
  for (const Job& job : plan.encodes) {
    const bool blocked = std::any_of(plan.runs.begin(), plan.runs.end(), [&](const PlannedRun& run) {
      return run.preparation_id == job.id && failed_preparations.count("synth/" + run.sequence);
    });
    if (blocked) {
      failed_preparations.insert(job.id);
    } else {
      encodes.push_back(job);
    }
  }
  if (!(options.stop_requested && options.stop_requested())) {
    const std::set<std::string> failed_encodes = prepare(encodes, out, options, "encodings", report);
    failed_preparations.insert(failed_encodes.begin(), failed_encodes.end());
  }

  if (options.stop_requested && options.stop_requested()) {
    report.stopped = true;  // no run is started or recorded as failed for an interrupted preparation
    return report;
  }

  std::vector<const PlannedRun*> todo;
  for (const PlannedRun& run : plan.runs) {
    const std::optional<json> previous = readJson(resultFile(run.job.output));
    if (previous && (previous->value("status", "") == "ok" || !options.retry_failed)) {
      ++report.skipped;
      continue;
    }
    if (failed_preparations.count(run.preparation_id)) {
      json result = summariseRun(run, std::nullopt, 0.0);
      result["status"] = "failed";
      result["reason"] =
          fmt::format("{} failed (see {})", run.preparation_id, (out / "logs" / logName(run.preparation_id)).string());
      writeFile(resultFile(run.job.output), result.dump(2) + "\n");
      ++report.ran;
      ++report.failed;
      if (report.first_failure.empty()) report.first_failure = run.job.id + ": " + result["reason"].get<std::string>();
      continue;
    }
    todo.push_back(&run);
  }
  if (options.progress) {
    fmt::print(stderr, "runs: {} to do, {} done before, {} in all ({} at a time)\n", todo.size(), report.skipped,
               report.total, std::max(1, options.jobs));
  }

  double busy_s = 0.0;
  int finished = 0;
  executeJobs(
      todo.size(), options.jobs, options.stop_requested,
      [&](std::size_t i) -> std::optional<pid_t> {
        const PlannedRun& run = *todo[i];
        fs::create_directories(run.job.output);
        for (const fs::path& file : {trajectoryFile(run.job.output), statisticsFile(run.job.output),
                                     resultFile(run.job.output), logFile(run.job.output)}) {
          fs::remove(file);
        }
        writeFile(run.job.output / "command.txt", shellCommand(run.job.argv) + "\n");
        return platform::startChild(run.job.argv, logFile(run.job.output));
      },
      [&](std::size_t i, const platform::ChildExit& exit, double seconds) {
        const PlannedRun& run = *todo[i];
        if (options.stop_requested && options.stop_requested() && interruptedBySignal(exit)) {
          report.stopped = true;  // not recorded: the next call runs it again
          return;
        }
        const json result = summariseRun(run, exit, seconds);
        writeFile(resultFile(run.job.output), result.dump(2) + "\n");
        ++report.ran;
        ++finished;
        busy_s += seconds;
        const bool ok = result.value("status", "") == "ok";
        if (!ok) {
          ++report.failed;
          if (report.first_failure.empty()) report.first_failure = run.job.id + ": " + result.value("reason", "");
        }
        if (!options.progress) return;
        const int done = report.skipped + report.ran;
        const std::size_t left = todo.size() - static_cast<std::size_t>(finished);
        const double eta_s = busy_s / finished * static_cast<double>(left) / std::max(1, options.jobs);
        const std::string outcome =
            ok ? fmt::format("ATE {:.2f} cm, RTE {}", 100.0 * result["ate_m"].get<double>(),
                             result["rte_m"].is_null()
                                 ? std::string("n/a")
                                 : fmt::format("{:.3f} cm", 100.0 * result["rte_m"].get<double>()))
               : "FAILED (x): " + result.value("reason", "");
        fmt::print(stderr, "[{}/{}] {}: {} ({:.1f} s), about {} left\n", done, report.total, run.job.id, outcome,
                   seconds, duration(eta_s));
      });
  if (options.stop_requested && options.stop_requested()) report.stopped = true;
  return report;
}

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
