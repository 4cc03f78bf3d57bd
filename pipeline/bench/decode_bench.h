#pragma once
// `voca bench decode`: decoder cost on this machine. Decodes a whole video, or both cameras of a VOCA
// video folder frame by frame as the pipeline does, held in memory on one thread, as (1) full decode
// with motion-vector export, (2) full decode without, (3) MV-only parse with the loop filter
// skipped, (4) full decode + MV with the deblocking filter skipped (voca run --skip-deblock), and,
// when libavcodec decodes luma only (lumaOnlyDecodingAvailable), (5) full decode + MV with chroma
// too; times every (stereo) frame with this thread's CPU clock and checks that (3) and (4) give the
// full decode's vectors and (5) its luma planes.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "drivers/decode/demuxer.h"

namespace voca::pipeline {

struct DecodeBenchOptions {
  std::filesystem::path input;       // a video file, or a VOCA video folder (both cameras)
  int repeat = 5;                    // timed runs per variant (after one warm-up run each)
  std::string decoder = "software";  // auto, software, vaapi or v4l2m2m for the full-decode variants
  bool progress = true;              // "repeat i/n" on stderr
};

struct DecodeVariantResult {
  std::string label;
  std::vector<double> frame_cpu_ms;  // every timed frame of every run: CPU time of all cameras' frame
  std::vector<double> run_wall_fps;  // per timed run: frames / wall time (lower when the cores are shared)
  double median_ms = 0.0, p99_ms = 0.0, mean_ms = 0.0;
  double cpu_fps = 0.0;  // frames per second of this thread's CPU time (from mean_ms)
  double median_wall_fps = 0.0;
};

struct DecodeBenchResult {
  std::vector<std::filesystem::path> videos;  // one per camera, decoded together per frame
  decode::StreamInfo stream;                  // the first camera's (all must have its size and codec)
  std::size_t packets = 0;                    // per camera
  double kbit_per_s = 0.0;                    // per camera, at the stream's frame rate (0 when unknown)
  double stream_fps = 0.0;                    // the stream's nominal rate (0 when unknown)
  // A VOCA video folder: the rate the frames were recorded at (data.csv timestamps), which the
  // paper's encoding does not keep (it codes at 30 fps whatever the dataset's rate), and the bitrate
  // per second of recording at that rate. 0 for a single video file.
  double recording_fps = 0.0;
  double recording_kbit_per_s = 0.0;
  double demux_packets_per_s = 0.0;           // reading the packets (not part of the timed runs)
  std::string decoder_description;            // the decoder actually used (auto may fall back)
  int frames = 0;                             // (stereo) frames per run
  double vectors_per_frame = 0.0;             // per camera frame
  bool parse_vectors_identical = false;       // MV-only parse and deblock-skipped decode == full decode's vectors
  bool luma_only = false;                     // libavcodec skips the chroma planes (built with --enable-gray)
  bool luma_only_identical = false;           // ... and the luma planes equal those of a decode with chroma
  std::vector<DecodeVariantResult> variants;  // full + MV, without MV, MV-only, unfiltered[, with chroma]
};

// Throws InputError for a bad --repeat, an unreadable video, one without packets, or cameras whose
// videos differ in codec or size.
DecodeBenchResult runDecodeBench(const DecodeBenchOptions& options);

}  // namespace voca::pipeline
