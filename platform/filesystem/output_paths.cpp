#include "platform/filesystem/output_paths.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>

#include <fmt/core.h>

#include "voca/core/error.h"

namespace voca {

namespace fs = std::filesystem;

namespace {

fs::path resolved(const fs::path& path) {
  std::error_code error;
  fs::path absolute = fs::absolute(path, error);
  if (error) return path.lexically_normal();
  fs::path canonical = fs::weakly_canonical(absolute, error);
  if (error) return absolute.lexically_normal();
  // "dir/" and "dir" are one folder.
  if (!canonical.has_filename() && canonical.has_parent_path()) canonical = canonical.parent_path();
  return canonical;
}

}  // namespace

bool isWithin(const fs::path& inner, const fs::path& outer) {
  const fs::path a = resolved(inner), b = resolved(outer);
  auto ia = a.begin();
  for (auto ib = b.begin(); ib != b.end(); ++ib, ++ia) {
    if (ib->empty()) continue;  // a trailing separator's empty element
    if (ia == a.end() || *ia != *ib) return false;
  }
  return true;
}

void requireOutputsApart(std::span<const NamedPath> outputs, std::span<const NamedPath> inputs) {
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    const NamedPath& out = outputs[o];
    if (out.path.empty()) continue;
    for (const NamedPath& in : inputs) {
      if (in.path.empty() || !isWithin(out.path, in.path)) continue;
      const bool same = resolved(out.path) == resolved(in.path);
      throw InputError(fmt::format("{} {} {} {} ({}), which this command reads; choose another path", out.what,
                                   out.path.string(), same ? "is" : "lies in", in.what, in.path.string()));
    }
    for (std::size_t other = 0; other < o; ++other) {
      if (outputs[other].path.empty() || resolved(outputs[other].path) != resolved(out.path)) continue;
      throw InputError(fmt::format("{} and {} name the same file {}; give each its own", outputs[other].what, out.what,
                                   out.path.string()));
    }
  }
}

void requireWritableFile(const NamedPath& output) {
  if (output.path.empty()) return;
  const fs::path& path = output.path;
  std::error_code error;
  if (fs::is_directory(path, error)) {
    throw InputError(fmt::format("cannot write {} {}: it is a folder", output.what, path.string()));
  }
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::is_directory(folder, error)) {
    throw InputError(
        fmt::format("cannot write {} {}: the folder {} does not exist", output.what, path.string(), folder.string()));
  }
  const bool exists = fs::exists(path, error);
  if (::access((exists ? path : folder).c_str(), W_OK) != 0) {
    throw InputError(fmt::format("cannot write {} {}: {}", output.what, path.string(), std::strerror(errno)));
  }
}

void requireNotDevice(const fs::path& input, const std::string& what) {
  std::error_code error;
  if (fs::is_character_file(input, error) || fs::is_block_file(input, error)) {
    throw InputError(fmt::format("{} {} is a device, not a file", what, input.string()));
  }
}

void requireFoldersApart(const NamedPath& output, const NamedPath& input) {
  if (output.path.empty() || input.path.empty()) return;
  // A folder inside the input is left alone: the layout written there (out/mav0/...) is new files.
  if (!isWithin(input.path, output.path)) return;
  const char* relation = resolved(output.path) == resolved(input.path) ? "is" : "holds";
  throw InputError(fmt::format("{} {} {} {} ({}); choose a folder apart from it", output.what, output.path.string(),
                               relation, input.what, input.path.string()));
}

}  // namespace voca
