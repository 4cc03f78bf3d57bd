#pragma once
// Helpers shared by the test suites: the shared reference data and scratch folders.

#include <doctest/doctest.h>

#include <filesystem>
#include <optional>
#include <random>
#include <string>

namespace voca::test {

// A file or folder under ../shared/data, or nullopt when the shared data is not beside the
// checkout (the project must build and pass without it). Tests that need it return early with
// a message, so the run says what it did not check.
inline std::optional<std::filesystem::path> sharedData(const std::string& relative) {
  const std::filesystem::path path = std::filesystem::path(VOCA_SHARED_DATA_DIR) / relative;
  if (!std::filesystem::exists(path)) {
    MESSAGE("skipped: shared data not found at " << path.string());
    return std::nullopt;
  }
  return path;
}

// A fresh folder under the build tree, removed when the test ends.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) {
    std::random_device seed;
    path_ = std::filesystem::path(VOCA_BINARY_DIR) / "test-scratch" / (name + "-" + std::to_string(seed()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace voca::test
