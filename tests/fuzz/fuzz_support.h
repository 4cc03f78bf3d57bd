#pragma once
// Shared by the libFuzzer targets: a private scratch folder per fuzzing process, writing the input
// where the parser expects its file, and the rule every target checks. The parsers are exercised
// through their public entry points on real files, because several of them read a folder layout
// (KITTI's image_0/ beside calib.txt, EuRoC's camN/ folders), so the file layout is part of the
// input; the scratch folder lives in TMPDIR (a RAM disk on most systems) and is removed at exit.
//
// The rule: bad input may only end in voca::InputError (or voca::RuntimeFailure where a codec
// library refuses the data). Any other exception, a crash, a leak or a sanitizer report is a bug.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>

#include <unistd.h>

#include "voca/core/error.h"

namespace voca::fuzz {

// The scratch folder of this process, created on first use and removed when the process exits.
inline const std::filesystem::path& scratchDir() {
  static const std::filesystem::path dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/voca-fuzz-XXXXXX";
    if (mkdtemp(pattern.data()) == nullptr) std::abort();
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(scratchDir(), ignored);
    });
    return std::filesystem::path(pattern);
  }();
  return dir;
}

// Writes bytes to scratchDir()/relative, creating folders; aborts if that fails (not a finding).
inline std::filesystem::path writeInput(const std::string& relative, const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = scratchDir() / relative;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) std::abort();
  return path;
}

inline std::filesystem::path writeInput(const std::string& relative, std::string_view text) {
  return writeInput(relative, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

// Runs one parse; the errors a user is meant to see end it, anything else escapes to libFuzzer.
template <typename F>
void expectOnlyInputErrors(F&& parse) {
  try {
    parse();
  } catch (const voca::InputError&) {
  } catch (const voca::RuntimeFailure&) {
  }
}

// Splits an input in two at the first occurrence of the separator line (for targets that read two
// files); without it, both parts are the whole input.
inline std::pair<std::string_view, std::string_view> splitInput(std::string_view input) {
  constexpr std::string_view kSeparator = "\n--8<--\n";
  const std::size_t at = input.find(kSeparator);
  if (at == std::string_view::npos) return {input, input};
  return {input.substr(0, at), input.substr(at + kSeparator.size())};
}

}  // namespace voca::fuzz
