#include "platform/filesystem/temp_dir.h"

#include <fmt/core.h>

#include <random>
#include <system_error>

#include "voca/core/error.h"

namespace voca {

TempDir::TempDir(std::string_view prefix) {
  std::random_device seed;
  const std::filesystem::path base = std::filesystem::temp_directory_path();
  // create_directory reports whether it made the folder, so a name already taken is never shared.
  for (int attempt = 0; attempt < 16; ++attempt) {
    path_ = base / fmt::format("{}-{:08x}", prefix, seed());
    std::error_code error;
    if (std::filesystem::create_directory(path_, error)) return;
  }
  throw RuntimeFailure(fmt::format("cannot create a temporary folder in {}", base.string()));
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace voca
