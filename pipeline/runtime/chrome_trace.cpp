#include "pipeline/runtime/chrome_trace.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "platform/filesystem/output_paths.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

// Trace times are microseconds with three decimals: nanoseconds survive the round trip exactly.
struct Micros {
  std::int64_t ns;
};

}  // namespace

}  // namespace voca::pipeline

template <>
struct fmt::formatter<voca::pipeline::Micros> {
  constexpr auto parse(format_parse_context& ctx) { return ctx.begin(); }
  template <typename Context>
  auto format(const voca::pipeline::Micros& t, Context& ctx) const {
    const bool negative = t.ns < 0;
    const std::uint64_t m =
        negative ? std::uint64_t{0} - static_cast<std::uint64_t>(t.ns) : static_cast<std::uint64_t>(t.ns);
    return fmt::format_to(ctx.out(), "{}{}.{:03d}", negative ? "-" : "", m / 1000, m % 1000);
  }
};

namespace voca::pipeline {

namespace {

const char* reasonName(ReleaseReason reason) {
  switch (reason) {
    case ReleaseReason::kDropped:
      return "dropped";
    case ReleaseReason::kDamaged:
      return "damaged";
    case ReleaseReason::kAborted:
      return "aborted";
    case ReleaseReason::kNotTracked:
      return "not tracked";
    default:
      return "done";
  }
}

// Trace thread ids of stage helpers: this plus the stage's position (pipeline threads are 1, 2, ...).
constexpr int kHelperTrackBase = 1001;

// A trace time in microseconds back to integer nanoseconds.
std::int64_t toNs(const nlohmann::json& value) {
  return static_cast<std::int64_t>(std::llround(value.get<double>() * 1000.0));
}

}  // namespace

ChromeTraceWriter::ChromeTraceWriter(const std::filesystem::path& path, std::int64_t origin_ns)
    : path_(path), origin_ns_(origin_ns) {
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) throw InputError(fmt::format("cannot write trace file {}", path.string()));
  frame_text_.reserve(std::size_t{4} << 10);  // a frame of eight stages and a helper takes under 2 KB
  const std::string_view head =
      "[\n{\"name\":\"process_name\",\"ph\":\"M\",\"pid\":1,\"args\":{\"name\":\"voca pipeline\"}}";
  write(head.data(), head.size());
}

ChromeTraceWriter::~ChromeTraceWriter() {
  if (file_ != nullptr) std::fclose(file_);
}

void ChromeTraceWriter::write(const char* data, std::size_t size) {
  if (file_ == nullptr || failed_) return;
  if (std::fwrite(data, 1, size, file_) != size) failed_ = true;
}

void ChromeTraceWriter::threadName(int thread, std::string_view name) {
  fmt::memory_buffer b;
  fmt::format_to(
      std::back_inserter(b),
      ",\n{{\"name\":\"thread_name\",\"ph\":\"M\",\"pid\":1,\"tid\":{},\"args\":{{\"name\":\"{}\"}}}}"
      ",\n{{\"name\":\"thread_sort_index\",\"ph\":\"M\",\"pid\":1,\"tid\":{},\"args\":{{\"sort_index\":{}}}}}",
      thread + 1, name, thread + 1, thread + 1);
  write(b.data(), b.size());
}

void ChromeTraceWriter::frame(const FrameSlot& slot, std::span<const std::string> stage_names,
                              std::span<const int> thread_of_stage) {
  frame_text_.clear();
  auto out = std::back_inserter(frame_text_);
  const std::int64_t index = slot.frameIndex();
  const std::size_t n = stage_names.size();
  for (std::size_t k = 0; k < n; ++k) {
    const StageTiming& t = slot.timing[k];
    const std::int64_t wait = k == 0 ? 0 : t.start_ns - slot.timing[k - 1].end_ns;
    fmt::format_to(out,
                   ",\n{{\"name\":\"{}\",\"cat\":\"stage\",\"ph\":\"X\",\"pid\":1,\"tid\":{},\"ts\":{},\"dur\":{},"
                   "\"args\":{{\"frame\":{},\"stage\":{},\"wait_us\":{},\"cpu_us\":{}}}}}",
                   stage_names[k], thread_of_stage[k] + 1, Micros{t.start_ns - origin_ns_},
                   Micros{t.end_ns - t.start_ns}, index, k, Micros{wait}, Micros{t.cpu_ns});
  }
  if (slot.helper_stage >= 0 && static_cast<std::size_t>(slot.helper_stage) < n) {
    // The helper's track sorts right after its stage's thread (the same sort index, a larger id).
    const auto k = static_cast<std::size_t>(slot.helper_stage);
    const int tid = kHelperTrackBase + slot.helper_stage;
    if (!helper_named_[k]) {
      helper_named_[k] = true;
      fmt::format_to(
          out,
          ",\n{{\"name\":\"thread_name\",\"ph\":\"M\",\"pid\":1,\"tid\":{},\"args\":{{\"name\":\"thread {} helper: "
          "{}\"}}}}"
          ",\n{{\"name\":\"thread_sort_index\",\"ph\":\"M\",\"pid\":1,\"tid\":{},\"args\":{{\"sort_index\":{}}}}}",
          tid, thread_of_stage[k], stage_names[k], tid, thread_of_stage[k] + 1);
    }
    const StageTiming& h = slot.helper_timing;
    fmt::format_to(out,
                   ",\n{{\"name\":\"{} helper\",\"cat\":\"helper\",\"ph\":\"X\",\"pid\":1,\"tid\":{},\"ts\":{},"
                   "\"dur\":{},\"args\":{{\"frame\":{},\"stage\":{},\"cpu_us\":{}}}}}",
                   stage_names[k], tid, Micros{h.start_ns - origin_ns_}, Micros{h.end_ns - h.start_ns}, index, k,
                   Micros{h.cpu_ns});
  }
  // The whole frame as an async slice (its own lane in Perfetto), from arrival to the last stage.
  fmt::format_to(out,
                 ",\n{{\"name\":\"frame\",\"cat\":\"latency\",\"ph\":\"b\",\"id\":{},\"pid\":1,\"ts\":{},"
                 "\"args\":{{\"frame\":{}}}}}"
                 ",\n{{\"name\":\"frame\",\"cat\":\"latency\",\"ph\":\"e\",\"id\":{},\"pid\":1,\"ts\":{}}}",
                 index, Micros{slot.arrival_ns - origin_ns_}, index, index,
                 Micros{slot.timing[n - 1].end_ns - origin_ns_});
  write(frame_text_.data(), frame_text_.size());
  if (file_ != nullptr && !failed_ && std::fflush(file_) != 0) failed_ = true;
}

void ChromeTraceWriter::released(const ReleasedFrame& frame, std::string_view stage_name) {
  fmt::memory_buffer b;
  fmt::format_to(std::back_inserter(b),
                 ",\n{{\"name\":\"{}\",\"cat\":\"release\",\"ph\":\"i\",\"s\":\"g\",\"pid\":1,\"ts\":{},"
                 "\"args\":{{\"frame\":{},\"stage\":\"{}\"}}}}",
                 reasonName(frame.reason), Micros{frame.time_ns - origin_ns_}, frame.frame_index, stage_name);
  write(b.data(), b.size());
}

void ChromeTraceWriter::close(const RunReport& report) {
  nlohmann::json summary = {{"name", "run summary"}, {"cat", "summary"}, {"ph", "i"}, {"s", "g"}, {"pid", 1}};
  summary["ts"] = 0;
  nlohmann::json stages = nlohmann::json::array();
  for (const StageReport& s : report.stages) {
    stages.push_back({{"name", s.name},
                      {"thread", s.thread},
                      {"core", s.core},
                      {"helper_core", s.helper_core},
                      {"queue_high_water", s.queue_high_water},
                      {"dropped", s.dropped},
                      {"damaged", s.damaged}});
  }
  summary["args"] = {{"stages", stages},
                     {"threads", report.threads},
                     {"produced", report.produced},
                     {"completed", report.completed},
                     {"wall_s", report.wall_s}};
  const std::string text = ",\n" + summary.dump() + "\n]\n";
  write(text.data(), text.size());
  const bool write_failed = failed_;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (write_failed || rc != 0) throw InputError(fmt::format("error writing trace file {}", path_.string()));
}

RunReport readTraceReport(const std::filesystem::path& path, bool* complete) {
  requireNotDevice(path, "trace file");
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("{}: cannot open the trace file", path.string()));
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  nlohmann::json events = nlohmann::json::parse(text, nullptr, false);
  if (events.is_discarded()) {
    // A run that was killed leaves the array open; the format allows that.
    events = nlohmann::json::parse(text + "\n]", nullptr, false);
  }
  if (events.is_discarded() && text.rfind("[\n{", 0) == 0) {
    // Killed in the middle of a write (or the disk filled): every event starts a line with ",\n{", so
    // the events before the last start are whole.
    if (const std::size_t last = text.rfind(",\n{"); last != std::string::npos) {
      text.resize(last);
      events = nlohmann::json::parse(text + "\n]", nullptr, false);
    }
  }
  if (events.is_discarded() || !events.is_array()) {
    throw InputError(fmt::format("{}: not a Chrome trace-event JSON array (as `--trace` writes)", path.string()));
  }
  RunReport report;
  bool summary_seen = false;
  std::map<std::int64_t, std::int64_t> frame_begin;
  // A stage index as --trace writes it: a whole number below the pipeline's most stages.
  constexpr auto kStageLimit = static_cast<std::size_t>(kMaxStages);
  const auto stageIndex = [&](const nlohmann::json& args) {
    const nlohmann::json& stage = args.at("stage");
    if (!stage.is_number_unsigned() || stage.get<std::size_t>() >= kStageLimit) {
      throw InputError(fmt::format("{}: malformed trace event (stage {}: expected a whole number below {})",
                                   path.string(), stage.dump(), kStageLimit));
    }
    return stage.get<std::size_t>();
  };
  const auto stageAt = [&](std::size_t k, const std::string& name) -> StageReport& {
    if (report.stages.size() <= k) report.stages.resize(k + 1);
    StageReport& s = report.stages[k];
    if (s.name.empty()) s.name = name;
    return s;
  };
  try {
    for (const nlohmann::json& e : events) {
      if (!e.is_object() || !e.contains("ph")) continue;
      const std::string ph = e.at("ph").get<std::string>();
      const std::string cat = e.value("cat", "");
      if (ph == "X" && cat == "stage") {
        const nlohmann::json& args = e.at("args");
        const std::size_t stage = stageIndex(args);
        StageReport& s = stageAt(stage, e.at("name").get<std::string>());
        s.thread = e.at("tid").get<int>() - 1;
        s.service.record(toNs(e.at("dur")));
        s.cpu.record(toNs(args.at("cpu_us")));
        if (stage > 0) s.wait.record(toNs(args.at("wait_us")));
        if (stage == 0) ++report.completed;
      } else if (ph == "X" && cat == "helper") {
        const nlohmann::json& args = e.at("args");
        StageReport& s = stageAt(stageIndex(args), "");
        s.helper_service.record(toNs(e.at("dur")));
        s.helper_cpu.record(toNs(args.at("cpu_us")));
      } else if (ph == "b" && cat == "latency") {
        frame_begin[e.at("id").get<std::int64_t>()] = toNs(e.at("ts"));
      } else if (ph == "e" && cat == "latency") {
        const auto it = frame_begin.find(e.at("id").get<std::int64_t>());
        if (it != frame_begin.end()) {
          report.end_to_end.record(toNs(e.at("ts")) - it->second);
          frame_begin.erase(it);
        }
      } else if (ph == "i" && cat == "release") {
        const std::string reason = e.at("name").get<std::string>();
        ReleasedFrame f;
        f.frame_index = e.at("args").at("frame").get<std::int64_t>();
        f.time_ns = toNs(e.at("ts"));
        f.reason = reason == "dropped"   ? ReleaseReason::kDropped
                   : reason == "damaged" ? ReleaseReason::kDamaged
                                         : ReleaseReason::kAborted;
        report.released.push_back(f);
        if (f.reason == ReleaseReason::kDropped) ++report.dropped;
        if (f.reason == ReleaseReason::kDamaged) ++report.damaged;
      } else if (ph == "i" && cat == "summary") {
        summary_seen = true;
        const nlohmann::json& args = e.at("args");
        report.threads = args.value("threads", 1);
        report.produced = args.value("produced", std::int64_t{0});
        report.wall_s = args.value("wall_s", 0.0);
        std::size_t k = 0;
        for (const nlohmann::json& stage : args.at("stages")) {
          if (k >= kStageLimit) {
            throw InputError(
                fmt::format("{}: malformed trace summary (more than {} stages)", path.string(), kStageLimit));
          }
          StageReport& s = stageAt(k++, stage.at("name").get<std::string>());
          s.thread = stage.value("thread", s.thread);
          s.core = stage.value("core", -1);
          s.helper_core = stage.value("helper_core", -1);
          s.queue_high_water = stage.value("queue_high_water", std::size_t{0});
          s.dropped = stage.value("dropped", std::int64_t{0});
          s.damaged = stage.value("damaged", std::int64_t{0});
        }
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: malformed trace event ({})", path.string(), e.what()));
  }
  if (report.stages.empty()) {
    throw InputError(fmt::format("{}: no pipeline stage events (is it a `voca ... --trace` file?)", path.string()));
  }
  if (!summary_seen) {
    // The summary says how many threads ran; without it, the distinct threads the stages ran on.
    std::set<int> threads;
    for (const StageReport& s : report.stages) threads.insert(s.thread);
    report.threads = static_cast<int>(threads.size());
  }
  if (complete != nullptr) *complete = summary_seen;
  return report;
}

std::string formatLatencyReport(const RunReport& r) {
  std::string text;
  auto out = std::back_inserter(text);
  constexpr auto ms = platform::nsToMs;
  fmt::format_to(out, "latency per stage over {} frames ({} thread{}), ms:\n", r.completed, r.threads,
                 r.threads == 1 ? "" : "s");
  fmt::format_to(out, "  {:<10} {:>7} {:>7} {:>7} {:>7}   {:>7} {:>7} {:>7}   {:>6} {:>5} {:>7} {:>7}\n", "stage",
                 "p50", "p90", "p99", "max", "wait50", "wait99", "cpu50", "thread", "core", "queue", "dropped");
  for (const StageReport& s : r.stages) {
    fmt::format_to(
        out, "  {:<10} {:7.3f} {:7.3f} {:7.3f} {:7.3f}   {:7.3f} {:7.3f} {:7.3f}   {:>6} {:>5} {:>7} {:>7}\n", s.name,
        ms(s.service.quantileNs(0.5)), ms(s.service.quantileNs(0.9)), ms(s.service.quantileNs(0.99)),
        ms(s.service.maxNs()), ms(s.wait.quantileNs(0.5)), ms(s.wait.quantileNs(0.99)), ms(s.cpu.quantileNs(0.5)),
        s.thread, s.core < 0 ? std::string("-") : std::to_string(s.core), s.queue_high_water, s.dropped + s.damaged);
    if (s.helper_service.count() > 0) {
      // The stage's helper thread, its part of each frame (it has no queue: the stage waits for it).
      fmt::format_to(out, "  {:<10} {:7.3f} {:7.3f} {:7.3f} {:7.3f}   {:>7} {:>7} {:7.3f}   {:>6} {:>5}\n", "+ helper",
                     ms(s.helper_service.quantileNs(0.5)), ms(s.helper_service.quantileNs(0.9)),
                     ms(s.helper_service.quantileNs(0.99)), ms(s.helper_service.maxNs()), "", "",
                     ms(s.helper_cpu.quantileNs(0.5)), s.thread,
                     s.helper_core < 0 ? std::string("-") : std::to_string(s.helper_core));
    }
  }
  const LatencyHistogram& e = r.end_to_end;
  fmt::format_to(out, "  {:<10} {:7.3f} {:7.3f} {:7.3f} {:7.3f}   (arrival to the end of the last stage)\n",
                 "end-to-end", ms(e.quantileNs(0.5)), ms(e.quantileNs(0.9)), ms(e.quantileNs(0.99)), ms(e.maxNs()));
  fmt::format_to(out, "frames: {} completed, {} dropped (live policy), {} damaged (skipped)\n", r.completed, r.dropped,
                 r.damaged);
  return text;
}

void printLatencyReport(const RunReport& report, std::FILE* out) {
  std::fputs(formatLatencyReport(report).c_str(), out);
}

}  // namespace voca::pipeline
