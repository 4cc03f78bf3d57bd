#pragma once
// Files in a suite's output folder, as every part of the harness reads and writes them.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace voca::harness {

// The JSON in file; nothing when it is absent, cut short or garbled (a crashed run's).
std::optional<nlohmann::json> readJson(const std::filesystem::path& file);

// Written to a temporary name and renamed, so a reader never sees half a file.
void writeFile(const std::filesystem::path& file, const std::string& text);

// Bytes of both cameras' videos in a VOCA video folder; 0 for raw images.
std::int64_t videoBytes(const std::filesystem::path& input);

}  // namespace voca::harness
