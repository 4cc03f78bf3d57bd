#include "pipeline/harness/suite.h"

#include <algorithm>
#include <fstream>
#include <set>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "drivers/encode/video_encoder.h"
#include "voca/core/error.h"
#include "voca/frontend/frontend_config.h"

namespace voca::harness {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kSuiteKeys =
    "name, sequences, bitrates, modes, bridging, configs, frames, encode_fps, decoded_png, run_args, rules, external";
constexpr const char* kSequenceKeys = "name, path, synth, calib, gt, config, encoded, optional";
constexpr const char* kRulesKeys = "ate_divergence_m, rte_divergence_m, min_reset_free_fraction";
constexpr const char* kExternalKeys = "system, sequence, bitrate, trajectory";

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw InputError(fmt::format("{}: {}", where, what));
}

std::string readString(const json& value, const std::string& where) {
  if (!value.is_string()) fail(where, fmt::format("expected a string, got {}", value.dump()));
  return value.get<std::string>();
}

std::vector<std::string> readStrings(const json& value, const std::string& where) {
  if (!value.is_array() || value.empty()) fail(where, "expected a non-empty array of strings");
  std::vector<std::string> result;
  for (std::size_t i = 0; i < value.size(); ++i)
    result.push_back(readString(value[i], fmt::format("{}[{}]", where, i)));
  return result;
}

double readPositive(const json& value, const std::string& where) {
  if (!value.is_number() || value.get<double>() <= 0.0) fail(where, fmt::format("expected a positive number"));
  return value.get<double>();
}

// Names become folder names and table labels: keep them plain.
std::string readName(const json& value, const std::string& where) {
  const std::string name = readString(value, where);
  if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") !=
                          std::string::npos) {
    fail(where, fmt::format("\"{}\": expected letters, digits, '_', '.' or '-'", name));
  }
  return name;
}

fs::path resolve(const fs::path& base, const std::string& text) {
  const fs::path path(text);
  return (path.is_absolute() ? path : base / path).lexically_normal();
}

SuiteSequence parseSequence(const json& value, const fs::path& base, const std::string& where) {
  if (!value.is_object()) fail(where, "expected an object with \"name\" and \"path\" or \"synth\"");
  SuiteSequence sequence;
  std::optional<std::string> path;
  for (const auto& [key, item] : value.items()) {
    const std::string at = where + "." + key;
    if (key == "name") {
      sequence.name = readName(item, at);
    } else if (key == "path") {
      path = readString(item, at);
    } else if (key == "synth") {
      sequence.synth_args = readStrings(item, at);
    } else if (key == "calib") {
      sequence.calibration = resolve(base, readString(item, at));
    } else if (key == "gt") {
      sequence.ground_truth = resolve(base, readString(item, at));
    } else if (key == "config") {
      sequence.config = readString(item, at);
    } else if (key == "encoded") {
      if (!item.is_object())
        fail(at, "expected an object: bitrate -> VOCA video folder, e.g. {\"500k\": \"V101-500k\"}");
      for (const auto& [bitrate, folder] : item.items()) {
        const std::string label = normaliseBitrate(bitrate, at);
        if (label == "raw") fail(at, "\"raw\" is the dataset itself, not an encoding");
        sequence.encoded[label] = resolve(base, readString(folder, at + "." + bitrate));
      }
    } else if (key == "optional") {
      if (!item.is_boolean()) fail(at, "expected true or false");
      sequence.optional = item.get<bool>();
    } else {
      fail(at, fmt::format("unknown key (known: {})", kSequenceKeys));
    }
  }
  if (sequence.name.empty()) fail(where, "missing \"name\"");
  if (path.has_value() == !sequence.synth_args.empty()) {
    fail(where, "give either \"path\" (a dataset folder) or \"synth\" (arguments of `voca synth`)");
  }
  if (path) sequence.path = resolve(base, *path);
  for (const std::string& arg : sequence.synth_args) {
    if (arg == "--out") fail(where + ".synth", "leave out --out: the suite chooses where the sequence is rendered");
  }
  if (sequence.calibration && !fs::exists(*sequence.calibration)) {
    fail(where + ".calib", fmt::format("{} does not exist", sequence.calibration->string()));
  }
  for (const auto& [bitrate, folder] : sequence.encoded) {
    if (!fs::is_directory(folder) && !sequence.optional) {
      fail(where + ".encoded." + bitrate, fmt::format("{} is not a folder", folder.string()));
    }
  }
  if (sequence.ground_truth && !fs::exists(*sequence.ground_truth) && !sequence.optional) {
    fail(where + ".gt", fmt::format("{} does not exist", sequence.ground_truth->string()));
  }
  return sequence;
}

TableRules parseRules(const json& value, const std::string& where) {
  if (!value.is_object()) fail(where, fmt::format("expected an object with {}", kRulesKeys));
  TableRules rules;
  for (const auto& [key, item] : value.items()) {
    const std::string at = where + "." + key;
    if (key == "ate_divergence_m") {
      rules.ate_divergence_m = readPositive(item, at);
    } else if (key == "rte_divergence_m") {
      rules.rte_divergence_m = readPositive(item, at);
    } else if (key == "min_reset_free_fraction") {
      if (!item.is_number() || item.get<double>() < 0.0 || item.get<double>() >= 1.0) fail(at, "expected 0 <= x < 1");
      rules.min_reset_free_fraction = item.get<double>();
    } else {
      fail(at, fmt::format("unknown key (known: {})", kRulesKeys));
    }
  }
  return rules;
}

ExternalRun parseExternal(const json& value, const fs::path& base, const std::string& where) {
  if (!value.is_object()) fail(where, fmt::format("expected an object with {}", kExternalKeys));
  ExternalRun run;
  for (const auto& [key, item] : value.items()) {
    const std::string at = where + "." + key;
    if (key == "system") {
      run.system = readString(item, at);
    } else if (key == "sequence") {
      run.sequence = readString(item, at);
    } else if (key == "bitrate") {
      run.bitrate = normaliseBitrate(readString(item, at), at);
    } else if (key == "trajectory") {
      run.trajectory = resolve(base, readString(item, at));
    } else {
      fail(at, fmt::format("unknown key (known: {})", kExternalKeys));
    }
  }
  if (run.system.empty() || run.sequence.empty() || run.trajectory.empty()) {
    fail(where, "needs \"system\", \"sequence\" and \"trajectory\"");
  }
  return run;
}

// A config's short name for labels and folders: a shipped name as is, a file by its stem.
std::string configLabel(const std::string& config) {
  if (config.empty()) return "default";
  return fs::path(config).stem().string();
}

}  // namespace

std::string normaliseBitrate(const std::string& text, const std::string& context) {
  if (text == "raw") return text;
  try {
    return encode::bitrateLabel(encode::parseBitrate(text));
  } catch (const InputError& e) {
    fail(context, fmt::format("\"{}\": expected \"raw\" or a bitrate such as 250k, 500k, 1M ({})", text, e.what()));
  }
}

Suite parseSuite(const json& root, const fs::path& base, const std::string& context) {
  if (!root.is_object()) fail(context, "expected a JSON object");
  Suite suite;
  bool have_sequences = false;
  for (const auto& [key, value] : root.items()) {
    const std::string at = context + ": " + key;
    if (key == "name") {
      suite.name = readName(value, at);
    } else if (key == "sequences") {
      if (!value.is_array() || value.empty()) fail(at, "expected a non-empty array of sequences");
      have_sequences = true;
      for (std::size_t i = 0; i < value.size(); ++i) {
        SuiteSequence sequence = parseSequence(value[i], base, fmt::format("{}[{}]", at, i));
        if (sequence.synth_args.empty() && !fs::is_directory(sequence.path)) {
          if (sequence.optional) {
            suite.notes.push_back(
                fmt::format("sequence {} skipped: {} does not exist", sequence.name, sequence.path.string()));
            continue;
          }
          fail(fmt::format("{}[{}].path", at, i),
               fmt::format("{} is not a folder (mark the sequence \"optional\": true to skip it when missing)",
                           sequence.path.string()));
        }
        suite.sequences.push_back(std::move(sequence));
      }
    } else if (key == "bitrates") {
      suite.bitrates.clear();
      for (const std::string& text : readStrings(value, at)) suite.bitrates.push_back(normaliseBitrate(text, at));
    } else if (key == "modes") {
      suite.modes = readStrings(value, at);
      for (const std::string& mode : suite.modes) requirePriorMode(mode, at);
    } else if (key == "bridging") {
      if (!value.is_array() || value.empty()) fail(at, "expected a non-empty array of true/false");
      suite.bridging.clear();
      for (const json& item : value) {
        if (!item.is_boolean()) fail(at, "expected true or false");
        suite.bridging.push_back(item.get<bool>());
      }
    } else if (key == "configs") {
      suite.configs.clear();
      for (const std::string& config : readStrings(value, at)) {
        // A file is resolved like every path; a shipped name (euroc, tumvi, kitti) has no extension.
        suite.configs.push_back(fs::path(config).has_extension() ? resolve(base, config).string() : config);
      }
    } else if (key == "frames") {
      if (!value.is_number_integer() || value.get<int>() < 0) fail(at, "expected 0 (all) or a positive frame count");
      suite.frames = value.get<int>();
    } else if (key == "encode_fps") {
      suite.encode_fps = value.is_number_integer() ? std::to_string(value.get<int>()) : readString(value, at);
    } else if (key == "decoded_png") {
      if (!value.is_boolean()) fail(at, "expected true or false");
      suite.decoded_png = value.get<bool>();
    } else if (key == "run_args") {
      suite.run_args = readStrings(value, at);
    } else if (key == "rules") {
      suite.rules = parseRules(value, at);
    } else if (key == "external") {
      if (!value.is_array()) fail(at, "expected an array");
      for (std::size_t i = 0; i < value.size(); ++i) {
        suite.external.push_back(parseExternal(value[i], base, fmt::format("{}[{}]", at, i)));
      }
    } else {
      fail(at, fmt::format("unknown key (known: {})", kSuiteKeys));
    }
  }
  if (!have_sequences) fail(context, "missing \"sequences\"");
  if (suite.sequences.empty()) fail(context, "none of the sequences exists");
  std::set<std::string> names;
  for (const SuiteSequence& sequence : suite.sequences) {
    if (!names.insert(sequence.name).second) fail(context, fmt::format("two sequences are named {}", sequence.name));
  }
  for (const auto* list : {&suite.bitrates, &suite.modes, &suite.configs}) {
    if (std::set<std::string>(list->begin(), list->end()).size() != list->size()) {
      fail(context, "bitrates, modes and configs must not repeat");
    }
  }
  for (const ExternalRun& run : suite.external) {
    if (!names.count(run.sequence)) {
      fail(context + ": external", fmt::format("{}: no sequence named {}", run.system, run.sequence));
    }
  }
  return suite;
}

Suite loadSuite(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(fmt::format("{}: cannot open the suite file", file.string()));
  json root;
  try {
    root = json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(fmt::format("{}: not valid JSON: {}", file.string(), e.what()));
  }
  return parseSuite(root, fs::absolute(file).parent_path(), file.string());
}

json suiteToJson(const Suite& suite) {
  json sequences = json::array();
  for (const SuiteSequence& s : suite.sequences) {
    json j = {{"name", s.name}};
    if (s.synth_args.empty()) {
      j["path"] = fs::absolute(s.path).string();
    } else {
      j["synth"] = s.synth_args;
    }
    if (s.calibration) j["calib"] = fs::absolute(*s.calibration).string();
    if (s.ground_truth) j["gt"] = fs::absolute(*s.ground_truth).string();
    if (s.config) j["config"] = *s.config;
    for (const auto& [bitrate, folder] : s.encoded) j["encoded"][bitrate] = fs::absolute(folder).string();
    sequences.push_back(j);
  }
  json external = json::array();
  for (const ExternalRun& e : suite.external) {
    external.push_back({{"system", e.system},
                        {"sequence", e.sequence},
                        {"bitrate", e.bitrate},
                        {"trajectory", fs::absolute(e.trajectory).string()}});
  }
  std::vector<std::string> configs;
  for (const std::string& config : suite.configs) {
    configs.push_back(config.empty() || !fs::path(config).has_extension() ? config : fs::absolute(config).string());
  }
  json j = {{"name", suite.name},
            {"sequences", sequences},
            {"bitrates", suite.bitrates},
            {"modes", suite.modes},
            {"bridging", suite.bridging},
            {"frames", suite.frames},
            {"encode_fps", suite.encode_fps},
            {"decoded_png", suite.decoded_png},
            {"rules",
             {{"ate_divergence_m", suite.rules.ate_divergence_m},
              {"rte_divergence_m", suite.rules.rte_divergence_m},
              {"min_reset_free_fraction", suite.rules.min_reset_free_fraction}}},
            {"external", external}};
  if (configs != std::vector<std::string>{""}) j["configs"] = configs;
  if (!suite.run_args.empty()) j["run_args"] = suite.run_args;
  return j;
}

SuitePlan planSuite(const Suite& suite, const fs::path& out, const std::string& voca) {
  SuitePlan plan;
  const bool several_configs = suite.configs.size() > 1;
  const auto systemName = [&](const std::string& mode, bool bridge, const std::string& config) {
    std::string name = mode;
    if (!bridge) name += " (no bridging)";
    if (several_configs) name += " [" + configLabel(config) + "]";
    return name;
  };
  for (const std::string& config : suite.configs) {
    for (const std::string& mode : suite.modes) {
      for (const bool bridge : suite.bridging) {
        if (mode == "none" && !bridge && std::count(suite.bridging.begin(), suite.bridging.end(), true) > 0) continue;
        const std::string name = systemName(mode, mode == "none" ? true : bridge, config);
        if (std::find(plan.systems.begin(), plan.systems.end(), name) == plan.systems.end()) {
          plan.systems.push_back(name);
        }
      }
    }
  }
  for (const ExternalRun& e : suite.external) {
    if (std::find(plan.systems.begin(), plan.systems.end(), e.system) == plan.systems.end()) {
      plan.systems.push_back(e.system);
    }
  }

  for (const SuiteSequence& sequence : suite.sequences) {
    fs::path raw_input = sequence.path;
    std::string synth_id;
    if (!sequence.synth_args.empty()) {
      raw_input = out / "sequences" / sequence.name;
      synth_id = "synth/" + sequence.name;
      std::vector<std::string> argv = {voca, "synth"};
      argv.insert(argv.end(), sequence.synth_args.begin(), sequence.synth_args.end());
      argv.insert(argv.end(), {"--out", raw_input.string()});
      plan.synth.push_back({synth_id, argv, raw_input});
    }
    const bool video_folder = fs::exists(raw_input / "mav0" / "cam0" / "data.mp4");
    const bool kitti = fs::is_directory(raw_input / "image_0") && fs::exists(raw_input / "times.txt");
    for (const std::string& bitrate : suite.bitrates) {
      fs::path input = raw_input;
      std::string preparation = synth_id;
      if (const auto given = sequence.encoded.find(bitrate); given != sequence.encoded.end()) {
        input = given->second;
        preparation.clear();
      } else if (bitrate != "raw") {
        input = out / "videos" / (sequence.name + "_" + bitrate);
        preparation = "encode/" + sequence.name + "_" + bitrate;
        std::vector<std::string> argv = {voca,    "encode", raw_input.string(), "--out", input.string(), "--bitrate",
                                         bitrate, "--fps",  suite.encode_fps};
        if (sequence.calibration) argv.insert(argv.end(), {"--calib", sequence.calibration->string()});
        if (suite.decoded_png) argv.insert(argv.end(), {"--decoded-png", input.string() + "_decoded"});
        plan.encodes.push_back({preparation, argv, input});
      }
      for (const std::string& suite_config : suite.configs) {
        std::string config = sequence.config.value_or(suite_config);
        // `voca run` picks the KITTI config for a KITTI folder itself, but its encodings are video folders.
        if (config.empty() && kitti) config = "kitti";
        for (const std::string& mode : suite.modes) {
          // Raw frames carry no motion vectors: every mode would be the baseline.
          if (bitrate == "raw" && !video_folder && mode != "none") continue;
          for (const bool bridge : suite.bridging) {
            const bool varies = mode != "none";
            if (!varies && !bridge && std::count(suite.bridging.begin(), suite.bridging.end(), true) > 0) continue;
            PlannedRun run;
            run.sequence = sequence.name;
            run.bitrate = bitrate;
            run.mode = mode;
            run.bridge = varies ? bridge : true;
            run.config = config;
            run.system = systemName(mode, run.bridge, suite_config);
            run.preparation_id = preparation;
            run.input = input;
            std::string id = sequence.name + "_" + bitrate + "_" + mode;
            if (!run.bridge) id += "_nobridge";
            if (several_configs) id += fmt::format("_{}", configLabel(suite_config));
            run.job.id = id;
            run.job.output = out / "runs" / id;
            std::vector<std::string>& argv = run.job.argv;
            argv = {voca,
                    "run",
                    input.string(),
                    "--out",
                    trajectoryFile(run.job.output).string(),
                    "--stats",
                    statisticsFile(run.job.output).string(),
                    "--mode",
                    mode};
            if (varies) argv.insert(argv.end(), {"--bridge", bridge ? "on" : "off"});
            if (!config.empty()) argv.insert(argv.end(), {"--config", config});
            if (sequence.calibration) argv.insert(argv.end(), {"--calib", sequence.calibration->string()});
            if (sequence.ground_truth) argv.insert(argv.end(), {"--gt", sequence.ground_truth->string()});
            if (suite.frames > 0) argv.insert(argv.end(), {"--frames", std::to_string(suite.frames)});
            argv.insert(argv.end(), suite.run_args.begin(), suite.run_args.end());
            plan.runs.push_back(std::move(run));
          }
        }
      }
    }
  }
  return plan;
}

std::string shellCommand(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& arg : argv) {
    if (!line.empty()) line += ' ';
    const bool plain = !arg.empty() && arg.find_first_not_of(
                                           "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                           "0123456789_.-/:=,+@%") == std::string::npos;
    if (plain) {
      line += arg;
      continue;
    }
    line += '\'';
    for (const char c : arg) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

}  // namespace voca::harness
