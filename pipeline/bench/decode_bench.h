#pragma once
// `voca bench decode`: decoder throughput on this machine. Decodes a whole video held in memory on
// one thread as (1) full decode with motion-vector export, (2) full decode without, (3) MV-only
// parse with the loop filter skipped, and checks that the parse gives the full decode's vectors.

#include <cstddef>
#include <string>
#include <vector>

#include "drivers/decode/demuxer.h"

namespace voca::pipeline {

struct DecodeBenchOptions {
  std::string video;
  int repeat = 5;                    // timed runs per variant (after one warm-up run each)
  std::string decoder = "software";  // auto, software, vaapi or v4l2m2m for the full-decode variants
  bool progress = true;              // "repeat i/n" on stderr
};

struct DecodeVariantResult {
  std::string label;
  std::vector<double> cpu_fps;   // per timed run: frames / this thread's CPU time
  std::vector<double> wall_fps;  // per timed run: frames / wall time (lower when the cores are shared)
  double median_cpu_fps = 0.0, min_cpu_fps = 0.0, max_cpu_fps = 0.0, median_wall_fps = 0.0;
};

struct DecodeBenchResult {
  decode::StreamInfo stream;
  std::size_t packets = 0;
  double kbit_per_s = 0.0;           // at the stream's frame rate (0 when unknown)
  double stream_fps = 0.0;           // the stream's nominal rate (0 when unknown)
  double demux_packets_per_s = 0.0;  // reading the packets (not part of the timed runs)
  std::string decoder_description;   // the decoder actually used (auto may fall back)
  int frames = 0;                    // per run
  double vectors_per_frame = 0.0;
  bool parse_vectors_identical = false;       // MV-only parse == full decode's vectors
  std::vector<DecodeVariantResult> variants;  // full + MV, full without MV, MV-only parse
};

// Throws InputError for a bad --repeat, an unreadable video or one without packets.
DecodeBenchResult runDecodeBench(const DecodeBenchOptions& options);

}  // namespace voca::pipeline
