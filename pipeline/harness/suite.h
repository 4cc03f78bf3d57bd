#pragma once
// A benchmark suite (`voca bench suite <suite.json>`): which sequences, bitrates, prior modes,
// bridging settings and configs to run, and the independent jobs that follow from it. Every job is
// one complete `voca` command line, so the same plan runs here (one child process per job) or on a
// cluster (`--emit-jobs`).

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "voca/eval/results_table.h"
#include "voca/frontend/frontend_config.h"

namespace voca::harness {

// One sequence: a dataset folder (EuRoC, TUM-VI, KITTI, VOCA video) or a `voca synth` rendering.
struct SuiteSequence {
  std::string name;
  std::filesystem::path path;                         // dataset folder; for synth: where it is rendered
  std::vector<std::string> synth_args;                // non-empty: `voca synth <args> --out <path>`
  std::optional<std::filesystem::path> calibration;   // overrides the one found with the dataset
  std::optional<std::filesystem::path> ground_truth;  // overrides the dataset's own (TUM, EuRoC csv, KITTI)
  std::optional<std::string> config;                  // overrides the suite's configs for this sequence
  // Encodings made elsewhere (e.g. by tools/make_eval_set.py), by bitrate: used instead of encoding.
  std::map<std::string, std::filesystem::path> encoded;
  bool optional = false;  // skipped (with a note) when the folder is missing
  // Failure bounds of its own instead of the suite's (keys left out take the paper's values), e.g. a
  // wider RTE bound for a street sequence.
  std::optional<TableRules> rules;
};

// A trajectory produced by another system (Basalt, ORB-SLAM3 ...) on one sequence at one bitrate,
// evaluated against the same ground truth and shown in the same tables.
struct ExternalRun {
  std::string system;
  std::string sequence;
  std::string bitrate = "raw";
  std::filesystem::path trajectory;  // missing file: shown as x (the system failed)
};

struct Suite {
  std::string name = "suite";
  std::vector<SuiteSequence> sequences;
  std::vector<std::string> bitrates = {"raw", "500k"};  // "raw" or a bitrate such as 500k, 1M
  std::vector<std::string> modes = {std::string(priorModeName(PriorMode::kNone)),
                                    std::string(priorModeName(PriorMode::kMvParallelOf))};
  std::vector<bool> bridging = {true};
  std::vector<std::string> configs = {""};  // shipped name or file; "" = the dataset's default
  int frames = 0;                           // 0 = all
  // Each run this many times, repeat r tracking from frame r * repeat_step_frames (`voca run
  // --start-frame`); the tables show the median over the repeats (medianOfRepeats). A deterministic VO's
  // error moves a lot with a small change of its input, so one run per cell overstates differences.
  int repeats = 1;
  int repeat_step_frames = 5;
  std::string encode_fps = "30";      // `voca encode --fps`: the paper's 30 for every dataset
  bool decoded_png = false;           // also write the decoded frames as EuRoC folders
  std::vector<std::string> run_args;  // appended to every `voca run` (e.g. --threads 1)
  TableRules rules;
  std::vector<ExternalRun> external;
  std::vector<std::string> notes;  // e.g. optional sequences that were not found
};

// Reads a suite file. Relative paths are relative to the file's folder. Throws InputError naming the
// file and the key for anything malformed: unknown keys, wrong types, unknown modes or bitrates,
// duplicate names, missing folders of non-optional sequences.
Suite loadSuite(const std::filesystem::path& file);
Suite parseSuite(const nlohmann::json& root, const std::filesystem::path& base_dir, const std::string& context);

// The suite with absolute paths, as written to <out>/suite.json (what `voca bench collect` reads).
nlohmann::json suiteToJson(const Suite& suite);

// "500k", "1M", "1000000" -> "500k", "1000k", "1000k"; "raw" stays. Throws InputError otherwise.
std::string normaliseBitrate(const std::string& text, const std::string& context);

// One independent job: its id, the command, and the folder it fills.
struct Job {
  std::string id;
  std::vector<std::string> argv;  // argv[0] is the voca executable
  std::filesystem::path output;   // synth/encode: the dataset folder; run: the run folder
};

// One VOCA-RT run of the suite.
struct PlannedRun {
  Job job;
  std::string sequence, bitrate, mode, config;
  int repeat = 0;            // 0 .. suite.repeats - 1
  std::string suite_config;  // the suite's config of its column (config is the sequence's own when it has one)
  bool bridge = true;
  std::string system;          // its column in the tables: mode, "no bridge", config when several
  std::string preparation_id;  // the synth or encode job it needs ("" = none)
  std::filesystem::path input;
};

// Everything to do, in dependency order: synth renderings, then encodings, then runs.
struct SuitePlan {
  std::vector<Job> synth;
  std::vector<Job> encodes;
  std::vector<PlannedRun> runs;
  std::vector<std::string> systems;  // column order: modes x bridging x configs, then external systems
};

// Folders under out: sequences/<name> (synth), videos/<sequence>_<bitrate> (encodings, with
// <..>_decoded beside when decoded_png), runs/<id>/ (trajectory.txt, stats.json, log.txt,
// result.json). Modes other than none need motion vectors, so raw runs of image datasets use mode none
// only (a VOCA video folder given as a sequence runs every mode at "raw", i.e. as recorded), and
// bridging only varies for modes with a prior.
SuitePlan planSuite(const Suite& suite, const std::filesystem::path& out, const std::string& voca_executable);

// The files of a run folder.
inline std::filesystem::path trajectoryFile(const std::filesystem::path& run_dir) { return run_dir / "trajectory.txt"; }
inline std::filesystem::path statisticsFile(const std::filesystem::path& run_dir) { return run_dir / "stats.json"; }
inline std::filesystem::path resultFile(const std::filesystem::path& run_dir) { return run_dir / "result.json"; }
inline std::filesystem::path logFile(const std::filesystem::path& run_dir) { return run_dir / "log.txt"; }

// A command line a POSIX shell reads back as argv (single quotes where needed).
std::string shellCommand(const std::vector<std::string>& argv);

}  // namespace voca::harness
