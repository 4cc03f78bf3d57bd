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

#include "pipeline/harness/suite_files.h"
#include "voca/core/error.h"

namespace voca::harness {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

std::string duration(double seconds) {
  const auto s = static_cast<long>(std::lround(seconds));
  if (s >= 3600) return fmt::format("{}h{:02}m", s / 3600, (s % 3600) / 60);
  return fmt::format("{}m{:02}s", s / 60, s % 60);
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

}  // namespace voca::harness
