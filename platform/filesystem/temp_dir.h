#pragma once
// A scratch folder that exists for the lifetime of one object (two-pass statistics, datasets
// encoded on the fly).

#include <filesystem>
#include <string_view>

namespace voca {

// A fresh folder <system temp>/<prefix>-<random hex>, removed with everything in it on destruction.
// Throws RuntimeFailure when no folder can be created.
class TempDir {
 public:
  explicit TempDir(std::string_view prefix = "voca");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace voca
