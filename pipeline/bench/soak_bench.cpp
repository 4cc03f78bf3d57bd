#include "pipeline/bench/soak_bench.h"

#include <fmt/core.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "drivers/decode/video_decoder.h"
#include "drivers/encode/dataset_encoder.h"
#include "drivers/source/looping_source.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "pipeline/harness/bench_sequence.h"
#include "pipeline/vo/vo_runner.h"
#include "pipeline/vo/vo_session.h"
#include "platform/filesystem/temp_dir.h"
#include "platform/memory/allocation_count.h"
#include "platform/memory/resident_memory.h"
#include "platform/realtime/clock.h"
#include "platform/terminal/progress_line.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

// One second between keyframes at 20 Hz: a drop or a damaged packet costs at most a second of frames.
constexpr int kLoopKeyframeInterval = 20;
constexpr std::int64_t kLoopBitrateBps = 500'000;

// The built-in loop: a 3 s moving sequence, rendered with one sample per pixel (faster; the soak
// measures the pipeline, not the tracker's accuracy).
harness::BenchSequenceSpec builtinLoopSpec() {
  harness::BenchSequenceSpec spec;
  spec.camera = "euroc";
  spec.motion = "gentle";
  spec.seconds = 3;
  spec.bitrate_bps = kLoopBitrateBps;
  spec.supersample = 1;
  spec.keyframe_interval = kLoopKeyframeInterval;
  return spec;
}

void checkOptions(const SoakOptions& o) {
  if (o.frames < 1) throw InputError(fmt::format("--frames: expected at least 1, got {}", o.frames));
  if (o.warmup < 0 || o.warmup >= o.frames) {
    throw InputError(
        fmt::format("--warmup: expected 0 to {} (fewer than --frames {}), got {}", o.frames - 1, o.frames, o.warmup));
  }
  const auto checkRate = [](double rate, const char* option) {
    if (!(rate >= 0.0 && rate < 1.0))
      throw InputError(fmt::format("{}: expected a rate in [0, 1), got {}", option, rate));
  };
  checkRate(o.drop_rate, "--drop-rate");
  checkRate(o.damage_rate, "--damage-rate");
  if (!(o.speed > 0.0)) throw InputError(fmt::format("--speed: expected a positive factor, got {}", o.speed));
  if (o.sample_interval < 1) {
    throw InputError(fmt::format("sample interval: expected at least 1 frame, got {}", o.sample_interval));
  }
  if (!(o.stall_timeout_s > 0.0)) {
    throw InputError(fmt::format("--stall-timeout: expected a positive time, got {}", o.stall_timeout_s));
  }
}

double mib(std::int64_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); }

// Sees every written frame: RSS samples, the steady state's allocation count, progress and the
// watchdog's heartbeat. Runs on the write stage's thread and allocates nothing per frame.
class SoakSink final : public FrameSink {
 public:
  SoakSink(const SoakOptions& options, const LoopingVideoSource& source)
      : options_(options), source_(source), last_written_ns_(platform::monotonicNs()) {
    samples_.reserve(static_cast<std::size_t>(options.frames / options.sample_interval + 2));
  }

  void consume(const FrameSlot& slot) override {
    const std::int64_t frame = slot.frameIndex();
    ++written_;
    if (!baseline_frame_ && frame >= options_.warmup) {
      baseline_frame_ = frame;
      baseline_allocations_ = platform::operatorNewCalls();
      at_warmup_ = platform::residentMemory();
      rss_peak_after_warmup_ = at_warmup_.bytes;
    }
    if (baseline_frame_) {
      last_frame_ = frame;
      last_allocations_ = platform::operatorNewCalls();
    }
    if (frame >= next_sample_) {
      const platform::ResidentMemory rss = platform::residentMemory();
      samples_.push_back({frame, rss.bytes, rss.anonymousBytes()});
      if (baseline_frame_) rss_peak_after_warmup_ = std::max(rss_peak_after_warmup_, rss.bytes);
      next_sample_ = (frame / options_.sample_interval + 1) * options_.sample_interval;
      if (options_.progress) showProgress(slot, frame, rss.bytes);
    }
    last_written_ns_.store(platform::monotonicNs(), std::memory_order_relaxed);
  }

  void finish() override {
    at_end_ = platform::residentMemory();
    samples_.push_back({last_frame_.value_or(-1), at_end_.bytes, at_end_.anonymousBytes()});
    if (baseline_frame_) rss_peak_after_warmup_ = std::max(rss_peak_after_warmup_, at_end_.bytes);
    line_.end();
  }

  std::int64_t lastWrittenNs() const { return last_written_ns_.load(std::memory_order_relaxed); }
  std::int64_t written() const { return written_; }

  void fill(SoakReport& report) const {
    report.rss = samples_;
    report.rss_at_warmup = at_warmup_.bytes;
    report.rss_at_end = at_end_.bytes;
    report.rss_peak_after_warmup = rss_peak_after_warmup_;
    report.rss_growth = baseline_frame_ ? at_end_.bytes - at_warmup_.bytes : 0;
    report.anonymous_growth = baseline_frame_ ? at_end_.anonymousBytes() - at_warmup_.anonymousBytes() : 0;
    if (baseline_frame_) {
      report.steady_frames = *last_frame_ - *baseline_frame_;
      report.steady_allocations = last_allocations_ - baseline_allocations_;
      report.allocations_per_frame = report.steady_frames > 0 ? static_cast<double>(report.steady_allocations) /
                                                                    static_cast<double>(report.steady_frames)
                                                              : 0.0;
    }
  }

 private:
  void showProgress(const FrameSlot& slot, std::int64_t frame, std::int64_t rss) {
    const SourceCounters lost = source_.counters();
    if (baseline_frame_) {
      line_.update(
          "soak: frame {}/{}: {} written, {} lost at the source, {} dropped, {} damaged; RSS {:.1f} MiB "
          "({:+.3f} since warm-up); {} allocations since warm-up",
          frame, options_.frames, written_, lost.frames_lost, slot.dropped_so_far, slot.damaged_so_far, mib(rss),
          mib(rss - at_warmup_.bytes), platform::operatorNewCalls() - baseline_allocations_);
    } else {
      line_.update(
          "soak: frame {}/{} (warm-up): {} written, {} lost at the source, {} dropped, {} damaged; RSS "
          "{:.1f} MiB",
          frame, options_.frames, written_, lost.frames_lost, slot.dropped_so_far, slot.damaged_so_far, mib(rss));
    }
  }

  const SoakOptions& options_;
  const LoopingVideoSource& source_;
  platform::ProgressLine line_;
  std::vector<RssSample> samples_;
  std::int64_t next_sample_ = 0;
  std::int64_t written_ = 0;
  std::optional<std::int64_t> baseline_frame_, last_frame_;
  std::int64_t baseline_allocations_ = 0, last_allocations_ = 0;
  platform::ResidentMemory at_warmup_, at_end_;
  std::int64_t rss_peak_after_warmup_ = 0;
  std::atomic<std::int64_t> last_written_ns_;
};

// Stops a session in which no frame has been written for the stall timeout; exits the process when
// the stop does not take either.
class Watchdog {
 public:
  Watchdog(VoSession& session, const SoakSink& sink, double timeout_s)
      : session_(session), sink_(sink), timeout_ns_(static_cast<std::int64_t>(timeout_s * 1e9)) {
    thread_ = std::thread([this] { watch(); });
  }
  ~Watchdog() {
    {
      const std::lock_guard lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

  // Empty unless it fired.
  const std::string& message() const { return message_; }

 private:
  void watch() {
    std::unique_lock lock(mutex_);
    std::int64_t stop_requested_ns = 0;
    while (!done_) {
      wake_.wait_for(lock, std::chrono::milliseconds(200));
      if (done_) break;
      const std::int64_t now = platform::monotonicNs();
      if (stop_requested_ns == 0 && now - sink_.lastWrittenNs() > timeout_ns_) {
        message_ = fmt::format("deadlock: no frame written for {:.0f} s (after {} frames written)",
                               static_cast<double>(timeout_ns_) / 1e9, sink_.written());
        stop_requested_ns = now;
        session_.requestStop();
      } else if (stop_requested_ns != 0 && now - stop_requested_ns > timeout_ns_) {
        std::fprintf(stderr, "\nvoca bench soak: %s; the pipeline did not stop within %.0f s either: exiting\n",
                     message_.c_str(), static_cast<double>(timeout_ns_) / 1e9);
        std::fflush(stderr);
        std::_Exit(kSoakDeadlockExitCode);
      }
    }
  }

  VoSession& session_;
  const SoakSink& sink_;
  std::int64_t timeout_ns_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::string message_;
  std::thread thread_;
};

// The recording to loop, as a VOCA video folder with a short GOP, and how it was made.
struct LoopInput {
  std::filesystem::path video;
  bool kitti = false;
};

std::optional<LoopInput> prepareLoop(const SoakOptions& options, const std::filesystem::path& work) {
  LoopInput loop;
  loop.video = work / "loop";
  if (options.input.empty()) {
    if (options.progress) {
      fmt::print(stderr, "soak: rendering and encoding the loop: {}\n",
                 harness::describeBenchSequence(builtinLoopSpec()));
    }
    if (!harness::generateBenchSequence(builtinLoopSpec(), loop.video, options.progress, options.stop_requested)) {
      return std::nullopt;
    }
    return loop;
  }
  const Dataset dataset = openDataset(options.input);
  if (dataset.layout == DatasetLayout::kVocaVideo) {
    loop.video = options.input;
    return loop;
  }
  loop.kitti = dataset.layout == DatasetLayout::kKitti;
  if (!encode::encodeForReplay(options.input, loop.video, kLoopBitrateBps, std::nullopt, options.progress,
                               options.stop_requested, kLoopKeyframeInterval)) {
    return std::nullopt;
  }
  return loop;
}

// Data rows of a trajectory file (lines that are not empty and not comments).
std::int64_t trajectoryRows(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(fmt::format("cannot read the soak's trajectory file {}", file.string()));
  std::int64_t rows = 0;
  std::string line;
  while (std::getline(in, line)) rows += !line.empty() && line[0] != '#' ? 1 : 0;
  return rows;
}

void judge(SoakReport& r) {
  if (!r.error.empty()) r.failures.push_back(fmt::format("a stage failed: {}", r.error));
  if (r.unaccounted != 0) {
    r.failures.push_back(fmt::format(
        "{} frames unaccounted for: {} in, {} written + {} lost at the source + {} "
        "dropped + {} damaged",
        r.unaccounted, r.frames_in, r.written, r.dropped_at_source + r.skipped_to_keyframe, r.dropped_live, r.damaged));
  }
  if (r.rss_growth >= kSoakMaxRssGrowthBytes) {
    r.failures.push_back(fmt::format("RSS grew by {:.3f} MiB after the warm-up (target: below {:.0f} MiB)",
                                     mib(r.rss_growth), mib(kSoakMaxRssGrowthBytes)));
  }
  if (r.steady_allocations > 0) {
    r.failures.push_back(fmt::format("{} allocations (operator new) in the steady state, {:.4f} per frame (target: 0)",
                                     r.steady_allocations, r.allocations_per_frame));
  }
  if (r.written == 0) r.failures.push_back("no pose written");
}

}  // namespace

SoakReport runSoak(const SoakOptions& options) {
  checkOptions(options);
  if (!platform::operatorNewCounted()) {
    throw RuntimeFailure(
        "this executable does not count allocations (platform/memory/counting_operator_new.h is not linked)");
  }
  TempDir work("voca-soak");
  SoakReport report;
  report.speed = options.speed;
  const std::optional<LoopInput> loop = prepareLoop(options, work.path());
  if (!loop) {
    report.stopped = true;
    return report;
  }
  decode::silenceDamageMessages();  // the damage is on purpose, and counted
  const Dataset dataset = openDataset(loop->video);
  if (!dataset.calibration) {
    throw InputError(fmt::format("{}: no calibration found beside the dataset", loop->video.string()));
  }
  const StereoRig rig = loadCalibration(*dataset.calibration);
  LoopingVideoSource source(dataset, LoopOptions{.frames = options.frames,
                                                 .drop_rate = options.drop_rate,
                                                 .damage_rate = options.damage_rate,
                                                 .seed = options.seed});
  report.input = source.info().description;
  report.frames_per_pass = source.framesPerPass();
  report.trajectory_file = options.trajectory_file.empty() ? work.path() / "trajectory.tum" : options.trajectory_file;

  SoakSink sink(options, source);
  VoRunOptions run;
  run.trajectory_file = report.trajectory_file;
  run.keep_trajectory = false;  // memory must not grow with the run: the file has every pose
  run.statistics_rows = 0;
  run.realtime = true;
  run.speed = options.speed;
  run.progress = false;
  run.pipeline_options.threads = 0;
  run.pipeline_options.stop_requested = options.stop_requested;
  run.extra_sinks = {&sink};
  VoRunResult result;
  std::string deadlock;
  {
    VoSession session(source, rig, resolveRunConfig(std::nullopt, loop->kitti).config, run);
    const Watchdog watchdog(session, sink, options.stall_timeout_s);
    session.run();
    deadlock = watchdog.message();
    result = session.takeResult();
  }
  const RunReport& pipeline = result.pipeline_report;
  const LoopCounters loop_counters = source.loopCounters();
  report.passes = loop_counters.passes;
  report.threads = pipeline.threads;
  report.wall_s = pipeline.wall_s;
  report.frames_in = loop_counters.frames;
  report.written = trajectoryRows(report.trajectory_file);
  report.dropped_at_source = loop_counters.dropped;
  report.skipped_to_keyframe = loop_counters.skipped;
  report.dropped_live = pipeline.dropped;
  report.damaged = pipeline.damaged;
  report.damaged_packets = loop_counters.damaged_packets;
  report.unaccounted = report.frames_in - report.written - report.dropped_at_source - report.skipped_to_keyframe -
                       report.dropped_live - report.damaged;
  report.tracker_resets = result.backend.resets;
  for (const StageReport& stage : pipeline.stages) {
    report.stages.push_back({stage.name, stage.queue_high_water, stage.dropped, stage.damaged});
  }
  sink.fill(report);
  report.stopped = pipeline.stopped && deadlock.empty();
  if (pipeline.error) {
    report.error =
        fmt::format("{} at frame {}: {}", pipeline.error->stage, pipeline.error->frame_index, pipeline.error->message);
  }
  if (!deadlock.empty()) report.failures.push_back(deadlock);
  // A run stopped by the user is incomplete, not failed: its numbers are what it reached.
  if (!report.stopped) judge(report);
  return report;
}

void writeSoakJson(const SoakReport& r, const std::filesystem::path& file) {
  nlohmann::json rss = nlohmann::json::array();
  for (const RssSample& s : r.rss) {
    rss.push_back({{"frame", s.frame}, {"bytes", s.bytes}, {"anonymous_bytes", s.anonymous_bytes}});
  }
  nlohmann::json stages = nlohmann::json::array();
  for (const SoakStage& s : r.stages) {
    stages.push_back(
        {{"name", s.name}, {"queue_high_water", s.queue_high_water}, {"dropped", s.dropped}, {"damaged", s.damaged}});
  }
  const nlohmann::json json = {
      {"input", r.input},
      {"trajectory_file", r.trajectory_file.string()},
      {"frames_per_pass", r.frames_per_pass},
      {"passes", r.passes},
      {"threads", r.threads},
      {"speed", r.speed},
      {"wall_s", r.wall_s},
      {"frames_in", r.frames_in},
      {"written", r.written},
      {"dropped_at_source", r.dropped_at_source},
      {"skipped_to_keyframe", r.skipped_to_keyframe},
      {"dropped_live", r.dropped_live},
      {"damaged", r.damaged},
      {"unaccounted", r.unaccounted},
      {"damaged_packets", r.damaged_packets},
      {"tracker_resets", r.tracker_resets},
      {"rss_at_warmup_bytes", r.rss_at_warmup},
      {"rss_at_end_bytes", r.rss_at_end},
      {"rss_peak_after_warmup_bytes", r.rss_peak_after_warmup},
      {"rss_growth_bytes", r.rss_growth},
      {"rss_anonymous_growth_bytes", r.anonymous_growth},
      {"rss_growth_limit_bytes", kSoakMaxRssGrowthBytes},
      {"rss", rss},
      {"steady_frames", r.steady_frames},
      {"steady_allocations", r.steady_allocations},
      {"allocations_per_frame", r.allocations_per_frame},
      {"stages", stages},
      {"stopped", r.stopped},
      {"error", r.error},
      {"failures", r.failures},
      {"passed", r.failures.empty() && !r.stopped},
  };
  std::ofstream out(file);
  out << json.dump(2) << '\n';
  if (!out) throw InputError(fmt::format("cannot write {}", file.string()));
}

}  // namespace voca::pipeline
