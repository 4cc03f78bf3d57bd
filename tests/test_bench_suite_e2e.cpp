// `voca bench suite` and `voca bench collect` end to end through the `voca` binary: a run that fails is
// recorded as x and the suite goes on, a second call runs nothing, --emit-jobs prints complete command
// lines, collect summarises runs that left outputs only, decoded frames and external trajectories;
// and the shipped default suite gives a complete table.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "tests/test_support.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Runs voca, returning its exit code and what it printed (stdout and stderr).
int runVocaCapture(const std::string& args, std::string& output, const fs::path& log) {
  const std::string command = std::string(VOCA_BINARY_DIR) + "/bin/voca " + args + " >" + log.string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  output = text.str();
  return status;
}

json readJson(const fs::path& file) {
  std::ifstream in(file);
  REQUIRE_MESSAGE(in.good(), "missing " << file.string());
  return json::parse(in);
}

std::string readText(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::vector<std::string>> readCsv(const fs::path& file) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (const char c : line) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        fields.push_back(field);
        field.clear();
      } else {
        field += c;
      }
    }
    fields.push_back(field);
    rows.push_back(fields);
  }
  return rows;
}

std::size_t countFiles(const fs::path& dir, const std::string& extension) {
  if (!fs::is_directory(dir)) return 0;
  return static_cast<std::size_t>(std::count_if(fs::directory_iterator(dir), fs::directory_iterator{},
                                                [&](const auto& e) { return e.path().extension() == extension; }));
}

}  // namespace

TEST_CASE("voca bench suite: failures recorded as x, resume, emit-jobs, collect, decoded frames, external systems") {
  voca::test::ScratchDir dir("bench-suite");
  // A configuration with an unknown key: `voca run` refuses it, so every run of that sequence fails.
  voca::test::writeText(dir / "broken_vo.json", R"({"frontend": {"no_such_key": 1}})");
  const fs::path out = dir / "out";
  // 10 frames of gentle motion at 250k, two modes; the broken sequence renders the same room.
  const json suite = {
      {"name", "e2e"},
      {"sequences",
       {{{"name", "room"}, {"synth", {"--motion", "gentle", "--seconds", "0.5", "--supersample", "1"}}},
        {{"name", "broken"},
         {"synth", {"--motion", "gentle", "--seconds", "0.5", "--supersample", "1"}},
         {"config", (dir / "broken_vo.json").string()}}}},
      {"bitrates", {"250k"}},
      {"modes", {"none", "mv_parallel_of"}},
      {"bridging", {true, false}},
      {"decoded_png", true},
      {"run_args", {"--threads", "1"}},
      {"external",
       {{{"system", "other"}, {"sequence", "room"}, {"bitrate", "250k"}, {"trajectory", (dir / "other.txt").string()}},
        {{"system", "other"},
         {"sequence", "broken"},
         {"bitrate", "250k"},
         {"trajectory", (dir / "missing.txt").string()}}}}};
  voca::test::writeText(dir / "suite.json", suite.dump(2));

  std::string output;
  REQUIRE(runVocaCapture("bench suite " + (dir / "suite.json").string() + " --out " + out.string() + " --jobs 2",
                         output, dir / "log1.txt") == 0);
  CAPTURE(output);
  CHECK(output.find("6 runs, 0 done before, 6 run now, 3 failed") != std::string::npos);
  CHECK(output.find("[6/6]") != std::string::npos);  // the progress line counts done/total
  // An external trajectory that is not there is x, and said: a mistyped path reads the same.
  CHECK(output.find("warning: other on broken at 250k: " + (dir / "missing.txt").string() + " does not exist") !=
        std::string::npos);

  const json ok = readJson(out / "runs" / "room_250k_mv_parallel_of" / "result.json");
  CHECK(ok["status"] == "ok");
  CHECK(ok["frames"] == 10);
  CHECK(ok["ate_m"].get<double>() < 0.05);  // a synthetic room at 250k: millimetres, far below 5 cm
  CHECK(ok["video_bytes"].get<long>() > 0);
  CHECK(fs::file_size(out / "runs" / "room_250k_mv_parallel_of" / "trajectory.txt") > 0);
  // Bridging reaches the run: the statistics say which setting it ran with.
  CHECK(readJson(out / "runs" / "room_250k_mv_parallel_of" / "stats.json")["bridge_iframes"] == true);
  CHECK(readJson(out / "runs" / "room_250k_mv_parallel_of_nobridge" / "stats.json")["bridge_iframes"] == false);
  const json failed = readJson(out / "runs" / "broken_250k_none" / "result.json");
  CHECK(failed["status"] == "failed");
  CHECK(failed["reason"].get<std::string>().find("no_such_key") != std::string::npos);

  // The decoded frames as a EuRoC folder, with what another system needs beside them.
  const fs::path decoded = out / "videos" / "room_250k_decoded";
  CHECK(countFiles(decoded / "mav0" / "cam0" / "data", ".png") == 10);
  CHECK(countFiles(decoded / "mav0" / "cam1" / "data", ".png") == 10);
  CHECK(fs::exists(decoded / "calib.json"));
  CHECK(fs::exists(decoded / "mav0" / "state_groundtruth_estimate0" / "data.csv"));

  const auto table = readText(out / "tables" / "250k.md");
  CAPTURE(table);
  // room: both modes and the external system (whose trajectory did not exist yet: x); broken: x everywhere.
  CHECK(table.find("| ATE none | ATE mv_parallel_of | ATE mv_parallel_of (no bridging) | ATE other |") !=
        std::string::npos);
  CHECK(table.find("| *broken* † | x | x | x | x | x | x | x | x |") != std::string::npos);

  // Second call: nothing to do.
  REQUIRE(runVocaCapture("bench suite " + (dir / "suite.json").string() + " --out " + out.string(), output,
                         dir / "log2.txt") == 0);
  CHECK(output.find("6 runs, 6 done before, 0 run now, 0 failed") != std::string::npos);

  // Jobs for a cluster: complete command lines, one per run; renderings and encodings as stages before.
  REQUIRE(runVocaCapture("bench suite " + (dir / "suite.json").string() + " --out " + out.string() + " --emit-jobs run",
                         output, dir / "jobs.txt") == 0);
  std::istringstream lines(output);
  std::string line;
  int jobs = 0;
  while (std::getline(lines, line)) {
    ++jobs;
    CHECK(line.find("/voca run ") != std::string::npos);
    CHECK(line.find("--stats " + (out / "runs").string()) != std::string::npos);
  }
  CHECK(jobs == 6);
  const std::string emit = "bench suite " + (dir / "suite.json").string() + " --out " + out.string() + " --emit-jobs ";
  REQUIRE(runVocaCapture(emit + "synth", output, dir / "synth.txt") == 0);
  CHECK(output.find("/voca synth --motion gentle") != std::string::npos);
  REQUIRE(runVocaCapture(emit + "encode", output, dir / "encode.txt") == 0);
  CHECK(output.find("/voca encode " + (out / "sequences" / "room").string()) != std::string::npos);

  // What a cluster job leaves: outputs without result.json. Run one emitted line by hand, as a job would.
  const fs::path run_dir = out / "runs" / "room_250k_none";
  const std::string emitted = readText(run_dir / "command.txt");
  fs::remove(run_dir / "result.json");
  fs::remove(run_dir / "stats.json");
  fs::remove(run_dir / "trajectory.txt");
  REQUIRE(std::system((emitted.substr(0, emitted.size() - 1) + " >/dev/null 2>&1").c_str()) == 0);
  // The other system's trajectory appears (here: a copy of VOCA-RT's, so the two must agree).
  fs::copy_file(run_dir / "trajectory.txt", dir / "other.txt");
  // And one run never ran: its cells are unknown, not failures.
  fs::remove_all(out / "runs" / "room_250k_mv_parallel_of");

  REQUIRE(runVocaCapture("bench collect " + out.string(), output, dir / "collect.txt") == 0);
  const json collected = readJson(run_dir / "result.json");
  CHECK(collected["status"] == "ok");
  const auto rows = readCsv(out / "tables" / "250k.csv");
  REQUIRE(rows.size() == 1 + 2 + 3);
  // Columns: row, greyed, then (value, shown, rank) for ATE none, mv_parallel_of, its no-bridging run, other; RTE
  const auto& room = rows[1];
  REQUIRE(room.size() == 2 + 3 * 8);
  CHECK(room[0] == "room");
  CHECK(room[5 + 1] == "?");  // mv_parallel_of's ATE: no result
  REQUIRE_FALSE(room[2].empty());
  REQUIRE_FALSE(room[11].empty());
  CHECK(std::stod(room[11]) == doctest::Approx(std::stod(room[2])).epsilon(1e-6));  // the same trajectory
  CHECK(readCsv(out / "results.csv").size() == 1 + 5 + 2);  // header, 5 runs with results, 2 external
}

TEST_CASE("voca bench suite: a call whose every run fails exits 1 and names the reason, not the --help pointer") {
  voca::test::ScratchDir dir("bench-suite-all-failed");
  const fs::path out = dir / "out";
  // An option `voca run` does not know: each run ends with a usage error (exit code 2).
  const json suite = {
      {"name", "all-failed"},
      {"sequences", {{{"name", "room"}, {"synth", {"--motion", "gentle", "--seconds", "0.25", "--supersample", "1"}}}}},
      {"bitrates", {"250k"}},
      {"modes", {"none", "mv"}},
      {"run_args", {"--no-such-option"}}};
  voca::test::writeText(dir / "suite.json", suite.dump(2));
  std::string output;
  const int status = runVocaCapture("bench suite " + (dir / "suite.json").string() + " --out " + out.string(), output,
                                    dir / "log.txt");
  CAPTURE(output);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 1);
  CHECK(output.find("2 runs, 0 done before, 2 run now, 2 failed") != std::string::npos);
  CHECK(output.find("error: every run of this call failed; the first: room_250k_") != std::string::npos);
  CHECK(output.find("--no-such-option") != std::string::npos);
  const json failed = readJson(out / "runs" / "room_250k_none" / "result.json");
  CHECK(failed["status"] == "failed");
  const std::string reason = failed["reason"].get<std::string>();
  CHECK(reason.find("--no-such-option") != std::string::npos);
  CHECK(reason.find("Run with --help") == std::string::npos);
  // The tables are still written, every cell x.
  CHECK(fs::exists(out / "tables" / "250k.md"));
}

TEST_CASE("voca bench suite with repeats: each cell is the median of runs tracking from later frames") {
  voca::test::ScratchDir dir("bench-suite-repeats");
  const fs::path out = dir / "out";
  const json suite = {
      {"name", "repeats"},
      {"sequences",
       {{{"name", "room"}, {"synth", {"--motion", "aggressive", "--seconds", "1", "--supersample", "1"}}}}},
      {"bitrates", {"raw"}},
      {"modes", {"none"}},
      {"repeats", 3},
      {"repeat_step_frames", 3},
      {"run_args", {"--threads", "1"}}};
  voca::test::writeText(dir / "suite.json", suite.dump(2));
  std::string output;
  REQUIRE(runVocaCapture("bench suite " + (dir / "suite.json").string() + " --out " + out.string() + " --jobs 2",
                         output, dir / "log.txt") == 0);
  CAPTURE(output);
  const auto results = readCsv(out / "results.csv");
  REQUIRE(results.size() == 1 + 3);
  const auto& header = results[0];
  const auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    REQUIRE(it != header.end());
    return static_cast<std::size_t>(it - header.begin());
  };
  std::vector<double> ate, rte;
  std::set<std::string> repeats;
  for (std::size_t r = 1; r < results.size(); ++r) {
    const auto& row = results[r];
    REQUIRE_MESSAGE(row[column("status")] == "ok", row[column("reason")]);
    repeats.insert(row[column("repeat")]);
    // 20 frames; repeat k tracks from frame 3k.
    CHECK(std::stoi(row[column("frames")]) == 20 - 3 * std::stoi(row[column("repeat")]));
    ate.push_back(std::stod(row[column("ate_m")]));
    rte.push_back(std::stod(row[column("rte_m")]));
  }
  CHECK(repeats == std::set<std::string>{"0", "1", "2"});
  std::sort(ate.begin(), ate.end());
  std::sort(rte.begin(), rte.end());
  // The table's one cell per metric: the middle repeat (columns: row, greyed, (value, shown, rank) ATE, RTE).
  const auto table = readCsv(out / "tables" / "raw.csv");
  REQUIRE(table.size() == 1 + 1 + 3);
  CHECK(table[1][0] == "room");
  CHECK(std::stod(table[1][2]) == doctest::Approx(ate[1]).epsilon(1e-6));
  CHECK(std::stod(table[1][5]) == doctest::Approx(rte[1]).epsilon(1e-6));
  CHECK(readText(out / "summary.md").find("median of 3 runs tracking from frames 0, 3, 6") != std::string::npos);
  CHECK(readText(out / "tables" / "raw.md").find("median of 3 runs from frames 0, 3, 6") != std::string::npos);

  // Bounds of the sequence's own: an RTE bound below what it reached makes its RTE cell divergent (the
  // suite's 10 cm would not), and the table names the sequence's bounds.
  json strict = suite;
  strict["sequences"][0]["rules"] = {{"rte_divergence_m", 1e-6}};
  voca::test::writeText(dir / "suite.json", strict.dump(2));
  REQUIRE(runVocaCapture("bench suite " + (dir / "suite.json").string() + " --out " + out.string(), output,
                         dir / "log2.txt") == 0);
  CHECK(output.find("3 runs, 3 done before, 0 run now") != std::string::npos);  // the runs are reused
  const auto bounded = readCsv(out / "tables" / "raw.csv");
  REQUIRE(bounded.size() == 1 + 1 + 3);
  CHECK(bounded[1][5].empty());  // RTE: no value, shown as divergent
  CHECK(bounded[1][6].find("∞") != std::string::npos);
  CHECK(std::stod(bounded[1][2]) == doctest::Approx(ate[1]).epsilon(1e-6));  // ATE keeps the paper's bound
  CHECK(readText(out / "tables" / "raw.md")
            .find("Sequences with bounds of their own: room (ATE > 10 m, RTE > 0.0001 cm") != std::string::npos);
}

TEST_CASE("the shipped default suite: every cell filled, sizes rise with bitrate, every mode in the summary") {
  voca::test::ScratchDir dir("default-suite");
  const fs::path suite = fs::path(VOCA_SOURCE_DIR) / "configs" / "bench_suite_default.json";
  std::string output;
  REQUIRE(runVocaCapture("bench suite " + suite.string() + " --out " + dir.path().string() + " --jobs 2", output,
                         dir / "log.txt") == 0);
  CAPTURE(output);
  const auto summary = readCsv(dir / "summary.csv");
  const json used = readJson(dir / "suite.json");
  const auto bitrates = used["bitrates"].get<std::vector<std::string>>();
  const auto modes = used["modes"].get<std::vector<std::string>>();
  for (const std::string& bitrate : bitrates) {
    for (const std::string& mode : modes) {
      const bool present = std::any_of(summary.begin(), summary.end(),
                                       [&](const auto& row) { return row[0] == mode && row[1] == bitrate; });
      CHECK_MESSAGE(present, mode << " at " << bitrate << " missing from summary.csv");
    }
    const auto table = readCsv(dir / "tables" / (bitrate + ".csv"));
    REQUIRE(table.size() == 1 + used["sequences"].size() + 3);
    for (const auto& row : table) {
      for (const std::string& cell : row) CHECK_MESSAGE(cell != "?", "a missing cell in " << bitrate << ".csv");
    }
  }
  // Encoded sizes per sequence rise with the bitrate (two-pass rate control hits its target).
  std::map<std::string, std::map<std::string, long>> bytes;  // sequence -> bitrate -> video bytes
  const auto results = readCsv(dir / "results.csv");
  const auto& header = results[0];
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  for (std::size_t r = 1; r < results.size(); ++r) {
    const auto& row = results[r];
    CHECK_MESSAGE(row[column("status")] == "ok", row[column("id")] << ": " << row[column("reason")]);
    bytes[row[column("sequence")]][row[column("bitrate")]] = std::stol(row[column("video_bytes")]);
  }
  for (const auto& [sequence_name, sizes] : bytes) {
    const std::string& sequence = sequence_name;  // CAPTURE takes it by reference: clang 14 needs a variable
    CAPTURE(sequence);
    REQUIRE(sizes.size() == bitrates.size());
    for (std::size_t i = 1; i < bitrates.size(); ++i) CHECK(sizes.at(bitrates[i]) > sizes.at(bitrates[i - 1]));
  }
  const std::string md = readText(dir / "summary.md");
  for (const std::string& mode : modes) CHECK(md.find("| " + mode + " |") != std::string::npos);
  // Every prior mode against `none` at every encoded bitrate, both metrics, on every sequence (all ran).
  CHECK(md.find("Prior modes against `none`") != std::string::npos);
  const auto against = readCsv(dir / "against_none.csv");
  std::size_t encoded_bitrates = 0;
  for (const std::string& bitrate : bitrates) encoded_bitrates += bitrate == "raw" ? 0 : 1;
  const std::size_t prior_modes = static_cast<std::size_t>(
      std::count_if(modes.begin(), modes.end(), [](const std::string& m) { return m != "none"; }));
  REQUIRE(against.size() == 1 + encoded_bitrates * prior_modes * 2);
  // The same figures recomputed from results.csv with the paper's thresholds (10 m ATE, 10 cm RTE;
  // these runs never reset).
  std::map<std::tuple<std::string, std::string, std::string>, std::pair<double, double>> errors;
  for (std::size_t r = 1; r < results.size(); ++r) {
    const auto& row = results[r];
    errors[{row[column("sequence")], row[column("bitrate")], row[column("mode")]}] = {std::stod(row[column("ate_m")]),
                                                                                      std::stod(row[column("rte_m")])};
  }
  for (std::size_t r = 1; r < against.size(); ++r) {
    const auto& row = against[r];
    CAPTURE(row[0]);
    CAPTURE(row[1]);
    CAPTURE(row[3]);
    CHECK(row[1] != "none");
    CHECK(row[2] == "none");
    const bool rte = row[3] == "rte";
    const double limit = rte ? 0.10 : 10.0;
    std::size_t compared = 0;
    double sum = 0.0;
    for (const auto& sequence : used["sequences"]) {
      const std::string name = sequence["name"].get<std::string>();
      const auto mine = errors.at({name, row[0], row[1]});
      const auto base = errors.at({name, row[0], "none"});
      const double a = rte ? mine.second : mine.first, b = rte ? base.second : base.first;
      if (a > limit || b > limit) continue;
      sum += a / b - 1.0;
      ++compared;
    }
    REQUIRE(compared > 0);
    CHECK(std::stoul(row[4]) == compared);
    CHECK(std::stod(row[5]) == doctest::Approx(sum / static_cast<double>(compared)).epsilon(1e-4));
    CHECK(std::stod(row[6]) >= std::stod(row[5]));  // the worst change is at least the mean
  }
}
