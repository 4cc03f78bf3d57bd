#pragma once
// Paths checked before a command works. Outputs against the inputs, before anything is written: an
// output that is an input file, or lies in an input folder, would destroy what the command reads; two
// outputs naming one file would overwrite each other. Inputs read whole: a device never ends.

#include <filesystem>
#include <span>
#include <string>

namespace voca {

// A path and what it is to the user ("-o", "--stats", "the ground truth").
struct NamedPath {
  std::string what;
  std::filesystem::path path;
};

// Whether `inner` is `outer` or lies inside it, on resolved paths (symlinks, `.` and `..` resolved as
// far as the path exists; the paths need not exist).
bool isWithin(const std::filesystem::path& inner, const std::filesystem::path& outer);

// Throws InputError naming both when an output is an input or lies inside an input folder, or when
// two outputs are one file. Empty paths are skipped.
void requireOutputsApart(std::span<const NamedPath> outputs, std::span<const NamedPath> inputs);

// Throws InputError, naming the path and the reason, when the file cannot be written where it is: its
// folder is missing or not writable, or the path is a folder. Creates nothing, so a command can check
// every output before its work instead of failing after it. An empty path is skipped.
void requireWritableFile(const NamedPath& output);

// Throws InputError naming the path when a file to be read to its end is a device (/dev/zero grew
// the reader's memory without bound). Regular files and pipes pass.
void requireNotDevice(const std::filesystem::path& input, const std::string& what);

// Throws InputError naming both when the output folder is the input folder or holds it: a command
// writing a dataset layout (out/mav0/..., out/calib.json) there could overwrite the input's files.
void requireFoldersApart(const NamedPath& output, const NamedPath& input);

}  // namespace voca
