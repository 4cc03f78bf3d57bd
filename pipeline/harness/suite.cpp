#include "pipeline/harness/suite.h"

#include <algorithm>
#include <set>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include "drivers/encode/video_encoder.h"
#include "formats/config/config_section.h"
#include "voca/core/error.h"
#include "voca/frontend/frontend_config.h"

namespace voca::harness {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw InputError(fmt::format("{}: {}", where, what));
}

// Names become folder names and table labels: keep them plain.
std::string readName(const ConfigValue& value, const std::string& where) {
  const std::string name = value.string(where);
  if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") !=
                          std::string::npos) {
    fail(where, fmt::format("\"{}\": expected letters, digits, '_', '.' or '-'", name));
  }
  return name;
}

template <class Config>
using Reader = ConfigReader<Config>;

// The thresholds' open bounds are checked after reading (ranges in the table are closed).
const ConfigField<TableRules> kRulesFields[] = {
    {"ate_divergence_m", &TableRules::ate_divergence_m},
    {"rte_divergence_m", &TableRules::rte_divergence_m},
    {"min_reset_free_fraction", &TableRules::min_reset_free_fraction},
};

// The rules as the suite file writes them (the keys of kRulesFields).
json rulesToJson(const TableRules& rules) {
  return {{"ate_divergence_m", rules.ate_divergence_m},
          {"rte_divergence_m", rules.rte_divergence_m},
          {"min_reset_free_fraction", rules.min_reset_free_fraction}};
}

void checkRules(const TableRules& rules, const std::string& where) {
  if (!(rules.ate_divergence_m > 0.0)) fail(where + ".ate_divergence_m", "expected a positive number");
  if (!(rules.rte_divergence_m > 0.0)) fail(where + ".rte_divergence_m", "expected a positive number");
  if (!(rules.min_reset_free_fraction >= 0.0 && rules.min_reset_free_fraction < 1.0)) {
    fail(where + ".min_reset_free_fraction", "expected 0 <= x < 1");
  }
}

const ConfigField<SuiteSequence> kSequenceFields[] = {
    {"name", Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) {
       s.name = readName(v, at);
     }}},
    {"path",
     Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) { s.path = v.path(at); }}},
    {"synth", &SuiteSequence::synth_args},
    {"calib", Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) {
       s.calibration = v.path(at);
     }}},
    {"gt", Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) {
       s.ground_truth = v.path(at);
     }}},
    {"config", Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) {
       s.config = v.string(at);
     }}},
    {"encoded", Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) {
       if (!v.json().is_object())
         fail(at, "expected an object: bitrate -> VOCA video folder, e.g. {\"500k\": \"V101-500k\"}");
       for (const auto& [bitrate, folder] : v.json().items()) {
         const std::string label = normaliseBitrate(bitrate, at);
         if (label == "raw") fail(at, "\"raw\" is the dataset itself, not an encoding");
         s.encoded[label] = ConfigValue(folder, v.baseDir()).path(at + "." + bitrate);
       }
     }}},
    {"optional", &SuiteSequence::optional},
    {"rules", Reader<SuiteSequence>{[](SuiteSequence& s, const ConfigValue& v, const std::string& at) {
       TableRules rules;
       v.readSection<TableRules>(at, kRulesFields, rules);
       checkRules(rules, at);
       s.rules = rules;
     }}},
};

// Checks what the table cannot: one of path and synth, no --out, files that must exist.
void checkSequence(const SuiteSequence& sequence, const std::string& where) {
  if (sequence.name.empty()) fail(where, "missing \"name\"");
  if (sequence.path.empty() == sequence.synth_args.empty()) {
    fail(where, "give either \"path\" (a dataset folder) or \"synth\" (arguments of `voca synth`)");
  }
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
}

const ConfigField<ExternalRun> kExternalFields[] = {
    {"system", &ExternalRun::system},
    {"sequence", &ExternalRun::sequence},
    {"bitrate", Reader<ExternalRun>{[](ExternalRun& r, const ConfigValue& v, const std::string& at) {
       r.bitrate = normaliseBitrate(v.string(at), at);
     }}},
    {"trajectory", Reader<ExternalRun>{[](ExternalRun& r, const ConfigValue& v, const std::string& at) {
       r.trajectory = v.path(at);
     }}},
};

const ConfigField<Suite> kSuiteFields[] = {
    {"name", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) { s.name = readName(v, at); }}},
    {"sequences", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       v.forEachItem(at, [&](const ConfigValue& item, const std::string& item_at) {
         SuiteSequence sequence;
         item.readSection<SuiteSequence>(item_at, kSequenceFields, sequence);
         checkSequence(sequence, item_at);
         if (sequence.synth_args.empty() && !fs::is_directory(sequence.path)) {
           if (!sequence.optional) {
             fail(item_at + ".path",
                  fmt::format("{} is not a folder (mark the sequence \"optional\": true to skip it when missing)",
                              sequence.path.string()));
           }
           s.notes.push_back(
               fmt::format("sequence {} skipped: {} does not exist", sequence.name, sequence.path.string()));
           return;
         }
         s.sequences.push_back(std::move(sequence));
       });
     }}},
    {"bitrates", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       s.bitrates.clear();
       for (const std::string& text : v.strings(at)) s.bitrates.push_back(normaliseBitrate(text, at));
     }}},
    {"modes", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       s.modes = v.strings(at);
       for (const std::string& mode : s.modes) requirePriorMode(mode, at);
     }}},
    {"bridging", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       s.bridging.clear();
       v.forEachItem(at, [&](const ConfigValue& item, const std::string& item_at) {
         s.bridging.push_back(item.boolean(item_at));
       });
     }}},
    {"configs", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       s.configs.clear();
       v.forEachItem(at, [&](const ConfigValue& item, const std::string& item_at) {
         // A file is resolved like every path; a shipped name (euroc, tumvi, kitti) has no extension.
         const std::string config = item.string(item_at);
         s.configs.push_back(fs::path(config).has_extension() ? item.path(item_at).string() : config);
       });
     }}},
    {"frames", &Suite::frames, 0.0, static_cast<double>(kConfigIntLimit)},
    {"repeats", &Suite::repeats, 1.0, 99.0},
    {"repeat_step_frames", &Suite::repeat_step_frames, 1.0, 10000.0},
    {"encode_fps", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       s.encode_fps = v.json().is_number_integer() ? std::to_string(v.json().get<int>()) : v.string(at);
     }}},
    {"decoded_png", &Suite::decoded_png},
    {"run_args", &Suite::run_args},
    {"rules", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       v.readSection<TableRules>(at, kRulesFields, s.rules);
       checkRules(s.rules, at);
     }}},
    {"external", Reader<Suite>{[](Suite& s, const ConfigValue& v, const std::string& at) {
       if (!v.json().is_array()) fail(at, fmt::format("expected an array, got {}", v.json().dump()));
       if (v.json().empty()) return;
       v.forEachItem(at, [&](const ConfigValue& item, const std::string& item_at) {
         ExternalRun run;
         item.readSection<ExternalRun>(item_at, kExternalFields, run);
         if (run.system.empty() || run.sequence.empty() || run.trajectory.empty()) {
           fail(item_at, "needs \"system\", \"sequence\" and \"trajectory\"");
         }
         s.external.push_back(std::move(run));
       });
     }}},
};

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
  Suite suite;
  readConfigFile<Suite>(root, context, kSuiteFields, suite, base);
  if (suite.sequences.empty()) {
    fail(context, suite.notes.empty() ? "missing \"sequences\"" : "none of the sequences exists");
  }
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
  const json root = readJsonFile(file, "suite file");
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
    if (s.rules) j["rules"] = rulesToJson(*s.rules);
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
            {"repeats", suite.repeats},
            {"repeat_step_frames", suite.repeat_step_frames},
            {"encode_fps", suite.encode_fps},
            {"decoded_png", suite.decoded_png},
            {"rules", rulesToJson(suite.rules)},
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
            for (int repeat = 0; repeat < suite.repeats; ++repeat) {
              PlannedRun run;
              run.repeat = repeat;
              run.sequence = sequence.name;
              run.bitrate = bitrate;
              run.mode = mode;
              run.bridge = varies ? bridge : true;
              run.config = config;
              run.suite_config = suite_config;
              run.system = systemName(mode, run.bridge, suite_config);
              run.preparation_id = preparation;
              run.input = input;
              std::string id = sequence.name + "_" + bitrate + "_" + mode;
              if (!run.bridge) id += "_nobridge";
              if (several_configs) id += fmt::format("_{}", configLabel(suite_config));
              if (repeat > 0) id += fmt::format("_r{}", repeat);  // repeat 0 keeps the id of a suite without repeats
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
              if (repeat > 0) {
                argv.insert(argv.end(), {"--start-frame", std::to_string(repeat * suite.repeat_step_frames)});
              }
              if (suite.frames > 0) argv.insert(argv.end(), {"--frames", std::to_string(suite.frames)});
              argv.insert(argv.end(), suite.run_args.begin(), suite.run_args.end());
              plan.runs.push_back(std::move(run));
            }
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
