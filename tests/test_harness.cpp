// The evaluation harness without running anything: suite files (validation with clear errors), the plan
// of jobs that follows from them, command lines, and the tables as Markdown, CSV and LaTeX.

#include <algorithm>
#include <nlohmann/json.hpp>
#include <set>

#include "pipeline/harness/suite.h"
#include "pipeline/harness/table_format.h"
#include "tests/test_support.h"

namespace fs = std::filesystem;
using nlohmann::json;
using voca::test::inputErrorOf;

namespace {

json synthSuite() {
  return json::parse(R"({
    "name": "t",
    "sequences": [{"name": "a", "synth": ["--seconds", "1"]}, {"name": "b", "synth": ["--motion", "gentle"]}],
    "bitrates": ["raw", "250k", "1M"],
    "modes": ["none", "of_then_mv", "mv_parallel_of"],
    "bridging": [true, false]
  })");
}

std::string errorOf(const json& suite) {
  return inputErrorOf([&] { voca::harness::parseSuite(suite, ".", "s.json"); });
}

}  // namespace

TEST_CASE("suite files: unknown keys, wrong values and missing folders are errors naming the key") {
  json suite = synthSuite();
  suite["bitrate"] = {"500k"};
  CHECK(errorOf(suite).find("s.json: bitrate: unknown key") != std::string::npos);

  suite = synthSuite();
  suite["sequences"][0]["frames"] = 10;
  CHECK(errorOf(suite).find("sequences[0].frames: unknown key") != std::string::npos);

  suite = synthSuite();
  suite["bitrates"] = {"fast"};
  CHECK(errorOf(suite).find("\"fast\": expected \"raw\" or a bitrate") != std::string::npos);

  suite = synthSuite();
  suite["modes"] = {"mv_parallel"};
  CHECK(errorOf(suite).find("mv_parallel") != std::string::npos);

  suite = synthSuite();
  suite["sequences"][1]["name"] = "a";
  CHECK(errorOf(suite).find("two sequences are named a") != std::string::npos);

  suite = synthSuite();
  suite["sequences"][0] = {{"name", "x"}, {"path", "/no/such/folder"}};
  CHECK(errorOf(suite).find("/no/such/folder is not a folder") != std::string::npos);
  suite["sequences"][0]["optional"] = true;  // now skipped with a note
  const voca::harness::Suite parsed = voca::harness::parseSuite(suite, ".", "s.json");
  CHECK(parsed.sequences.size() == 1);
  REQUIRE(parsed.notes.size() == 1);
  CHECK(parsed.notes[0].find("sequence x skipped") != std::string::npos);

  suite = synthSuite();
  suite["sequences"][0]["synth"] = {"--out", "x"};
  CHECK(errorOf(suite).find("leave out --out") != std::string::npos);

  suite = synthSuite();
  suite["sequences"][1]["rules"] = {{"rte_divergence_m", 0}};
  CHECK(errorOf(suite).find("sequences[1].rules.rte_divergence_m: expected a positive number") != std::string::npos);
  suite["sequences"][1]["rules"] = {{"rte_divrgence_m", 1}};
  CHECK(errorOf(suite).find("sequences[1].rules.rte_divrgence_m: unknown key") != std::string::npos);
  suite["sequences"][1]["rules"] = {{"rte_divergence_m", 1.5}};
  {
    const voca::harness::Suite own = voca::harness::parseSuite(suite, ".", "s.json");
    CHECK_FALSE(own.sequences[0].rules);
    REQUIRE(own.sequences[1].rules);
    CHECK(own.sequences[1].rules->rte_divergence_m == 1.5);
    CHECK(own.sequences[1].rules->ate_divergence_m == voca::TableRules{}.ate_divergence_m);  // the paper's
    const voca::harness::Suite again = voca::harness::parseSuite(voca::harness::suiteToJson(own), ".", "again");
    REQUIRE(again.sequences[1].rules);
    CHECK(again.sequences[1].rules->rte_divergence_m == 1.5);
  }

  suite = synthSuite();
  suite["repeats"] = 0;
  CHECK(errorOf(suite).find("s.json: repeats: expected a value in [1, 99], got 0") != std::string::npos);
  suite = synthSuite();
  suite["repeat_step_frames"] = 0.5;
  CHECK(errorOf(suite).find("repeat_step_frames: expected an integer") != std::string::npos);

  suite = synthSuite();
  suite["rules"] = {{"ate_divergence_m", -1}};
  CHECK(errorOf(suite).find("rules.ate_divergence_m: expected a positive number") != std::string::npos);

  suite = synthSuite();
  suite["external"] = {{{"system", "Basalt"}, {"sequence", "zz"}, {"trajectory", "t.txt"}}};
  CHECK(errorOf(suite).find("Basalt: no sequence named zz") != std::string::npos);

  CHECK(inputErrorOf([] { voca::harness::loadSuite("/no/such/suite.json"); }).find("cannot open") != std::string::npos);
  {
    voca::test::ScratchDir dir("harness-suite-json");
    std::ofstream(dir / "huge.json") << R"({"sequences": [{"name": "a", "seconds": 1e400}]})";
    const std::string path = (dir / "huge.json").string();
    CHECK(inputErrorOf([&] { voca::harness::loadSuite(path); }).find("huge.json: not valid JSON") != std::string::npos);
  }
  CHECK(voca::harness::normaliseBitrate("1M", "x") == "1000k");
  CHECK(voca::harness::normaliseBitrate("raw", "x") == "raw");
}

TEST_CASE("planSuite: one encoding per sequence and bitrate, raw runs the baseline only, bridging only with a prior") {
  json suite = synthSuite();
  suite["external"] = {{{"system", "Basalt"}, {"sequence", "a"}, {"bitrate", "250k"}, {"trajectory", "t.txt"}}};
  suite["frames"] = 30;
  const voca::harness::Suite parsed = voca::harness::parseSuite(suite, "/base", "s.json");
  const voca::harness::SuitePlan plan = voca::harness::planSuite(parsed, "/out", "/bin/voca");
  CHECK(plan.synth.size() == 2);
  CHECK(plan.encodes.size() == 4);  // 2 sequences x 2 bitrates
  // Per sequence: raw none (1) + per encoded bitrate none (1) + 2 modes x 2 bridging = 1 + 2 * 5.
  CHECK(plan.runs.size() == 2 * 11);
  CHECK(plan.systems == std::vector<std::string>{"none", "of_then_mv", "of_then_mv (no bridging)", "mv_parallel_of",
                                                 "mv_parallel_of (no bridging)", "Basalt"});
  std::set<std::string> ids;
  for (const auto& run : plan.runs) {
    ids.insert(run.job.id);
    if (run.bitrate == "raw") CHECK(run.mode == "none");
    CHECK(run.job.argv[0] == "/bin/voca");
    CHECK(run.job.argv[1] == "run");
    const std::string line = voca::harness::shellCommand(run.job.argv);
    CHECK(line.find("--frames 30") != std::string::npos);
    CHECK(line.find("--stats /out/runs/" + run.job.id + "/stats.json") != std::string::npos);
    if (run.mode != "none") CHECK(line.find(run.bridge ? "--bridge on" : "--bridge off") != std::string::npos);
    if (run.bitrate != "raw") CHECK(run.input == fs::path("/out/videos") / (run.sequence + "_" + run.bitrate));
  }
  CHECK(ids.size() == plan.runs.size());  // every run has its own folder
  CHECK(voca::harness::shellCommand(plan.encodes[0].argv) ==
        "/bin/voca encode /out/sequences/a --out /out/videos/a_250k --bitrate 250k --fps 30");
  CHECK(voca::harness::shellCommand({"voca", "it's here", ""}) == "voca 'it'\\''s here' ''");

  // The suite written to the output folder reads back to the same plan.
  const voca::harness::Suite again = voca::harness::parseSuite(voca::harness::suiteToJson(parsed), "/x", "again");
  CHECK(voca::harness::planSuite(again, "/out", "/bin/voca").runs.size() == plan.runs.size());
}

TEST_CASE("planSuite: repeats track from later frames, each its own folder; repeat 0 is the run without repeats") {
  json suite = synthSuite();
  suite["bitrates"] = {"500k"};
  suite["modes"] = {"none", "mv_parallel_of"};
  suite["bridging"] = {true};
  suite["frames"] = 30;
  const voca::harness::SuitePlan single =
      voca::harness::planSuite(voca::harness::parseSuite(suite, "/base", "s.json"), "/out", "/bin/voca");
  suite["repeats"] = 3;
  suite["repeat_step_frames"] = 4;
  const voca::harness::Suite parsed = voca::harness::parseSuite(suite, "/base", "s.json");
  const voca::harness::SuitePlan plan = voca::harness::planSuite(parsed, "/out", "/bin/voca");
  REQUIRE(plan.runs.size() == 3 * single.runs.size());
  CHECK(plan.encodes.size() == single.encodes.size());  // repeats share the encoding
  std::set<std::string> ids;
  for (std::size_t i = 0; i < plan.runs.size(); ++i) {
    const voca::harness::PlannedRun& run = plan.runs[i];
    ids.insert(run.job.id);
    const voca::harness::PlannedRun& first = single.runs[i / 3];
    CHECK(run.repeat == static_cast<int>(i % 3));
    CHECK(run.system == first.system);
    const std::string line = voca::harness::shellCommand(run.job.argv);
    CAPTURE(line);
    CHECK(line.find("--frames 30") != std::string::npos);
    if (run.repeat == 0) {
      CHECK(run.job.id == first.job.id);  // results of a suite without repeats still count
      CHECK(run.job.argv == first.job.argv);
    } else {
      CHECK(run.job.id == first.job.id + "_r" + std::to_string(run.repeat));
      CHECK(line.find("--start-frame " + std::to_string(4 * run.repeat)) != std::string::npos);
    }
  }
  CHECK(ids.size() == plan.runs.size());
  const voca::harness::Suite again = voca::harness::parseSuite(voca::harness::suiteToJson(parsed), "/x", "again");
  CHECK(again.repeats == 3);
  CHECK(again.repeat_step_frames == 4);
}

TEST_CASE("planSuite: encodings made elsewhere are used as given; a video folder runs every mode as recorded") {
  voca::test::ScratchDir dir("harness-plan");
  voca::test::writeText(dir / "video" / "mav0" / "cam0" / "data.mp4", "");  // only its presence is looked at
  fs::create_directories(dir / "seq-500k");
  const json suite = {{"sequences",
                       {{{"name", "v"}, {"path", (dir / "video").string()}},
                        {{"name", "s"}, {"synth", {"--seconds", "1"}}, {"encoded", {{"500k", "seq-500k"}}}}}},
                      {"bitrates", {"raw", "500k"}},
                      {"modes", {"none", "mv_parallel_of"}}};
  const voca::harness::Suite parsed = voca::harness::parseSuite(suite, dir.path(), "s.json");
  const voca::harness::SuitePlan plan = voca::harness::planSuite(parsed, "/out", "voca");
  CHECK(plan.encodes.size() == 1);  // only v at 500k; s's 500k exists already
  CHECK(plan.encodes[0].id == "encode/v_500k");
  int video_raw = 0;
  for (const auto& run : plan.runs) {
    if (run.sequence == "v" && run.bitrate == "raw") ++video_raw;
    if (run.sequence == "s" && run.bitrate == "500k") {
      CHECK(run.input == dir / "seq-500k");
      CHECK(run.preparation_id.empty());
    }
  }
  CHECK(video_raw == 2);  // both modes: the video carries motion vectors

  // A KITTI folder keeps its config once encoded (the video folder would otherwise get the EuRoC one).
  fs::create_directories(dir / "kitti" / "image_0");
  voca::test::writeText(dir / "kitti" / "times.txt", "0.0\n");
  const json kitti = {{"sequences", {{{"name", "k"}, {"path", (dir / "kitti").string()}}}}, {"bitrates", {"500k"}}};
  for (const auto& run :
       voca::harness::planSuite(voca::harness::parseSuite(kitti, dir.path(), "k.json"), "/out", "voca").runs) {
    CHECK(voca::harness::shellCommand(run.job.argv).find("--config kitti") != std::string::npos);
  }
  // Several suite configs and a sequence with its own: each run knows its column's config, which is
  // what pairs a prior mode with its `none` in the summary, even where the run's own config is the same.
  const json columns = {{"sequences", {{{"name", "s"}, {"synth", {"--seconds", "1"}}, {"config", "tumvi"}}}},
                        {"bitrates", {"250k"}},
                        {"modes", {"none", "mv_parallel_of"}},
                        {"configs", {"euroc", "kitti"}}};
  const voca::harness::SuitePlan by_column =
      voca::harness::planSuite(voca::harness::parseSuite(columns, dir.path(), "c.json"), "/out", "voca");
  REQUIRE(by_column.runs.size() == 4);
  for (const auto& run : by_column.runs) {
    CAPTURE(run.system);
    CHECK(run.config == "tumvi");
    CHECK(run.system.find("[" + run.suite_config + "]") != std::string::npos);
  }
  json missing = suite;
  missing["sequences"][1]["encoded"]["1M"] = "nowhere";
  CHECK(inputErrorOf([&] { voca::harness::parseSuite(missing, dir.path(), "s.json"); }).find("encoded.1000k: ") !=
        std::string::npos);
}

TEST_CASE("tables as Markdown, CSV and LaTeX: values in cm, failures, emphasis, greyed rows") {
  using voca::RunMetrics;
  using voca::RunOutcome;
  const voca::ResultsTable table = voca::buildResultsTable(
      {{"none"}, {"mv_parallel_of"}}, {"s1", "s2"},
      {{RunMetrics{RunOutcome::kCompleted, 0.1234, 0.01234, 1.0}, RunMetrics{RunOutcome::kCompleted, 0.1, 0.02, 1.0}},
       {RunMetrics{RunOutcome::kCrashed, 0, std::nullopt, 0}, RunMetrics{RunOutcome::kCompleted, 20.0, 0.02, 1.0}}});
  const std::string md = voca::harness::tableMarkdown(table, "T", {});
  CHECK(md.find("| s1 | <u>12.34</u> | **10.00** | **1.234** | <u>2.000</u> |") != std::string::npos);
  CHECK(md.find("| *s2* † | x | ∞ | x | **2.000** |") != std::string::npos);
  CHECK(md.find("| **SR** | **50.0%** | **50.0%** | <u>50.0%</u> | **100.0%** |") != std::string::npos);

  const std::string tex = voca::harness::tableLatex(table, "T_1", {});
  CHECK(tex.find("\\toprule") != std::string::npos);
  CHECK(tex.find("\\bottomrule") != std::string::npos);
  CHECK(tex.find("s1 & \\underline{12.34} & \\textbf{10.00} & & \\textbf{1.234} & \\underline{2.000} \\\\") !=
        std::string::npos);
  CHECK(tex.find("\\color{gray}s2 & \\color{gray}$\\times$ & \\color{gray}$\\infty$") != std::string::npos);
  CHECK(tex.find("T\\_1") != std::string::npos);

  const std::string csv = voca::harness::tableCsv(table);
  CHECK(csv.find("s1,0,0.1234,12.34,2,0.1,10.00,1,") != std::string::npos);
  CHECK(csv.find("s2,1,,x,0,,∞,0,") != std::string::npos);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 1 + 2 + 3);  // header, sequences, AVG MED SR
}
