#pragma once
// The VOCA-RT configuration file: one JSON object with a "frontend" and a "backend" section, each
// read through its key table by the one section reader (config_section.h) and validated by its
// component (unknown keys, wrong types and out-of-range values are errors).

#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "voca/backend/backend_config.h"
#include "voca/frontend/frontend_config.h"

namespace voca {

// Everything a run is configured with. Sections missing from the file keep their defaults (the
// paper's EuRoC values).
struct VocaConfig {
  FrontendConfig frontend;
  BackendConfig backend;
};

// Reads and validates a config file, or a shipped configuration by name ("euroc", "tumvi",
// "kitti": configs/<name>_vo.json, compiled in) when no such file exists. Throws InputError naming
// the file and the key, e.g. "configs/x.json: frontend.pattern: expected 24 or 52, got 30".
VocaConfig loadConfig(const std::filesystem::path& file_or_name);

// The shipped configuration by name, or InputError listing the names there are.
VocaConfig builtinConfig(const std::string& name);

// Validates an already parsed document; `context` prefixes error messages (usually the file name).
VocaConfig parseConfig(const nlohmann::json& root, const std::string& context);

// The "frontend" section. Every key is optional (default = paper value), unknown keys are errors,
// and each value is checked for type and range. `context` names the section in messages, e.g.
// "file.json: frontend".
FrontendConfig parseFrontendConfig(const nlohmann::json& section, const std::string& context);

// The "backend" section: every key optional (default = paper value), unknown keys and out-of-range
// values are InputError naming the key, e.g. "file.json: backend.max_keyframes: expected a value in
// [2, 9], got 12".
BackendConfig parseBackendConfig(const nlohmann::json& section, const std::string& context);

}  // namespace voca
