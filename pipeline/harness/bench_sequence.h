#pragma once
// The moving synthetic sequences the throughput benchmarks measure when given no input: rendered
// as `voca synth --motion aggressive` does and encoded like the paper's videos, once, into a cache
// folder that later calls reuse. Static or sparse clips make a tracker look faster than it is on
// what users run, so the default is a sequence with fast motion and texture everywhere.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace voca::harness {

struct BenchSequenceSpec {
  std::string camera = "euroc";  // a `voca synth --camera` preset: euroc (752x480) or tumvi (512x512)
  std::string motion = "aggressive";
  int seconds = 40;
  std::int64_t bitrate_bps = 500'000;
  int supersample = 3;        // `voca synth --supersample`: 1 renders faster, with rougher edges
  int keyframe_interval = 0;  // frames between keyframes; 0: the paper's encoding (keyint 1000)
};

// Where generated sequences are kept: $XDG_CACHE_HOME/voca, else $HOME/.cache/voca. Throws InputError
// when neither variable is set.
std::filesystem::path benchCacheRoot();

// The VOCA video folder of a spec under root: <root>/bench/<camera>-<motion>-<seconds>s-<bitrate>.
std::filesystem::path benchSequenceFolder(const BenchSequenceSpec& spec, const std::filesystem::path& root);

// The config a spec's camera is measured with (the shipped config of the same name).
std::string benchSequenceConfig(const BenchSequenceSpec& spec);

// "moving euroc sequence (752x480 synthetic, aggressive motion, 40 s, 500kbit/s)", for headers.
std::string describeBenchSequence(const BenchSequenceSpec& spec);

// Renders spec (as `voca synth`) into a scratch folder beside video and encodes it into the VOCA video
// folder video, both in this process; the rendering is removed afterwards. Progress goes to stderr
// when asked. False when stop_requested() turned true (checked between frames); throws InputError
// for an invalid spec.
bool generateBenchSequence(const BenchSequenceSpec& spec, const std::filesystem::path& video, bool progress,
                           const std::function<bool()>& stop_requested);

// The video folder of spec under root, generating it first when it is missing: rendering (as
// `voca synth`) and the two-pass encoding, both in this process. Work goes into *.partial folders
// that are renamed when complete, so a folder that exists is whole and an interrupted generation
// starts over. Progress goes to stderr when asked. Returns nullopt when stop_requested() turned
// true (checked between frames); throws InputError for an invalid spec.
std::optional<std::filesystem::path> ensureBenchSequence(const BenchSequenceSpec& spec,
                                                         const std::filesystem::path& root, bool progress,
                                                         const std::function<bool()>& stop_requested);

}  // namespace voca::harness
