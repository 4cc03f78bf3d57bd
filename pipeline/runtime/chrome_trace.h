#pragma once
// The latency trace as a Chrome trace-event file (JSON array format; opens in Perfetto and
// chrome://tracing): one track per pipeline thread with a slice per frame and stage (and one per
// stage helper thread, its slice of each frame's work beside the stage's), an async slice
// per frame from arrival to the end of the last stage, an instant event per dropped or damaged
// frame, and a closing summary event. Written as frames complete, one flush per frame, so a stopped
// run leaves a readable file (the array format tolerates a missing closing bracket).
// readTraceReport() reads such a file back into the same statistics the run printed (a file cut inside
// an event, up to that event).

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "pipeline/runtime/runner.h"

namespace voca::pipeline {

class ChromeTraceWriter {
 public:
  // origin_ns: the monotonic time shown as 0. Throws InputError when the file cannot be created.
  ChromeTraceWriter(const std::filesystem::path& path, std::int64_t origin_ns);
  ~ChromeTraceWriter();
  ChromeTraceWriter(const ChromeTraceWriter&) = delete;
  ChromeTraceWriter& operator=(const ChromeTraceWriter&) = delete;

  void threadName(int thread, std::string_view name);
  // A completed frame: one slice per stage (stage k ran on thread_of_stage[k]) and the stage helper's
  // slice, if one ran; does not allocate.
  void frame(const FrameSlot& slot, std::span<const std::string> stage_names, std::span<const int> thread_of_stage);
  void released(const ReleasedFrame& frame, std::string_view stage_name);
  // The run's totals and queue high-water marks, then the closing bracket.
  void close(const RunReport& report);

 private:
  void write(const char* data, std::size_t size);
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::int64_t origin_ns_ = 0;
  bool failed_ = false;
  std::array<bool, kMaxStages> helper_named_{};  // whether a stage's helper track has its name yet
  std::string frame_text_;                       // one frame's events, reused: its capacity is reserved once
};

// Reads a trace written by ChromeTraceWriter: per-stage service, wait and CPU histograms, end to end,
// queue high-water marks, drops and damaged frames. Throws InputError naming the file when it is not
// such a trace. A trace without its closing summary (the run was killed) gives what its events hold:
// the threads counted from the stage events, no queue high-water marks; *complete says which.
RunReport readTraceReport(const std::filesystem::path& path, bool* complete = nullptr);

// p50/p90/p99/max per stage and end to end, queue high-water marks, drops: the `--profile` table.
std::string formatLatencyReport(const RunReport& report);
void printLatencyReport(const RunReport& report, std::FILE* out);

}  // namespace voca::pipeline
