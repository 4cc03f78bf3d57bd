#include "pipeline/harness/suite_files.h"

#include <fstream>

#include <fmt/core.h>

#include "voca/core/error.h"

namespace voca::harness {

namespace fs = std::filesystem;
using nlohmann::json;

std::optional<json> readJson(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return std::nullopt;
  try {
    return json::parse(in);
  } catch (const json::exception&) {
    return std::nullopt;  // a file cut short or garbled by a crash: treated as absent
  }
}

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

std::int64_t videoBytes(const fs::path& input) {
  std::int64_t bytes = 0;
  for (const char* camera : {"cam0", "cam1"}) {
    std::error_code error;
    const auto size = fs::file_size(input / "mav0" / camera / "data.mp4", error);
    if (!error) bytes += static_cast<std::int64_t>(size);
  }
  return bytes;
}

}  // namespace voca::harness
