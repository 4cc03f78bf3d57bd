#pragma once
// `voca bench soak`: the live pipeline run for a long time on an endless source, to show that it
// holds its memory, allocates nothing per frame, accounts for every frame and never hangs. A short
// recording (a built-in synthetic sequence, or any dataset, encoded with a short GOP) is looped by
// drivers/source/looping_source.h at a multiple of real time, with frames dropped and packets
// damaged at random, through the same staged pipeline and live policy as `voca run --realtime`; the
// poses go to a trajectory file through the normal trajectory sink.
//
// Measured: resident memory every sample_interval frames, its growth after the warm-up; operator new
// calls over the steady state (the frames after the warm-up; process-wide, so every thread counts);
// each stage's queue high-water mark; and frames in = poses written + lost at the source + dropped by
// the live policy + damaged. A watchdog ends a run in which no frame completes for stall_timeout_s.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace voca::pipeline {

struct SoakOptions {
  std::int64_t frames = 72'000;  // an hour at 20 Hz
  std::int64_t warmup = 1'000;   // frames before the steady state is measured
  double drop_rate = 0.002;      // chance per frame that the source drops it (then waits for a keyframe)
  double damage_rate = 0.002;    // chance per frame that one camera's packet is damaged
  std::uint64_t seed = 1;
  double speed = 5.0;  // multiple of the recording's real time
  // A dataset folder to loop (raw or VOCA video; raw ones are encoded with a short GOP first); empty: a
  // built-in synthetic sequence rendered and encoded into a scratch folder.
  std::filesystem::path input;
  std::filesystem::path trajectory_file;  // empty: in the scratch folder, removed afterwards
  std::int64_t sample_interval = 1'000;   // frames between RSS samples and progress updates
  double stall_timeout_s = 30.0;          // no frame written for this long: a deadlock
  bool progress = true;                   // generation and the run's progress on stderr
  std::function<bool()> stop_requested;   // polled between frames; true ends the run early
};

// The targets a soak must meet.
inline constexpr std::int64_t kSoakMaxRssGrowthBytes = 1 << 20;  // growth after the warm-up stays below

struct RssSample {
  std::int64_t frame = 0;  // the frame index written when it was taken
  std::int64_t bytes = 0;
  std::int64_t anonymous_bytes = 0;  // heap, stacks: what a leak grows (the rest maps files, such as code)
};

struct SoakStage {
  std::string name;
  std::size_t queue_high_water = 0;  // most frames waiting in front of it (0 when it shares a thread)
  std::int64_t dropped = 0;          // live policy, in front of it
  std::int64_t damaged = 0;          // released by it as undecodable
};

struct SoakReport {
  std::string input;  // the looped recording, one line
  std::filesystem::path trajectory_file;
  std::int64_t frames_per_pass = 0;
  std::int64_t passes = 0;
  int threads = 0;
  double speed = 0.0;
  double wall_s = 0.0;
  // Every frame index the source gave out, and where each went.
  std::int64_t frames_in = 0;
  std::int64_t written = 0;              // poses written (rows in the trajectory file)
  std::int64_t dropped_at_source = 0;    // dropped at random
  std::int64_t skipped_to_keyframe = 0;  // lost after a drop until both cameras' next keyframe
  std::int64_t dropped_live = 0;         // dropped by the live policy (the pipeline fell behind)
  std::int64_t damaged = 0;              // found undecodable by the decoder (or predicted from such a frame)
  std::int64_t unaccounted = 0;          // frames_in less all of the above; 0 when every frame is accounted for
  std::int64_t damaged_packets = 0;      // packets the source damaged
  std::int64_t tracker_resets = 0;       // the backend started over (loop seams, losses)
  // Memory.
  std::vector<RssSample> rss;  // every sample_interval frames from the start, and one at the end
  std::int64_t rss_at_warmup = 0, rss_at_end = 0, rss_peak_after_warmup = 0;
  std::int64_t rss_growth = 0;          // rss_at_end - rss_at_warmup: the target
  std::int64_t anonymous_growth = 0;    // of which anonymous memory (heap, stacks); the rest is file pages
  std::int64_t steady_frames = 0;       // frame indices from the warm-up's end to the last frame written
  std::int64_t steady_allocations = 0;  // operator new calls, process-wide, over those frames
  double allocations_per_frame = 0.0;
  std::vector<SoakStage> stages;  // source first
  bool stopped = false;           // a stop request ended the run early
  std::string error;              // a stage failed: which, at which frame, why
  // Targets missed, each naming which and by how much; empty: the soak passed.
  std::vector<std::string> failures;
};

// Runs the soak. Throws InputError for bad options (naming the option) and an input that cannot be
// looped; RuntimeFailure when this executable does not count allocations. When no frame is written
// for stall_timeout_s the run is stopped and reported as a deadlock; when it does not stop within
// another stall_timeout_s either, the message goes to stderr and the process exits with
// kSoakDeadlockExitCode, since no thread of the pipeline can be trusted to return.
SoakReport runSoak(const SoakOptions& options);
inline constexpr int kSoakDeadlockExitCode = 3;

// The report as JSON (every field above). Throws InputError when the file cannot be written.
void writeSoakJson(const SoakReport& report, const std::filesystem::path& file);

}  // namespace voca::pipeline
