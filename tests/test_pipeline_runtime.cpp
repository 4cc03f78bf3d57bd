// The staged runner on its own, with stand-in stages: every thread layout keeps every frame and its
// order offline; the live policy's drops are exactly the frames missing downstream; a throwing stage
// stops the run with its name and frame, finishes what was past it and never hangs; a stop request
// drains; latency histograms and the Chrome trace agree; a stage's helper thread hands work back
// and forth.

#include <doctest/doctest.h>

#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "pipeline/runtime/chrome_trace.h"
#include "pipeline/runtime/latency_histogram.h"
#include "pipeline/runtime/runner.h"
#include "pipeline/runtime/stage_helper.h"
#include "tests/test_support.h"

using namespace voca;
using namespace voca::pipeline;

namespace {

// Frames 0..count-1, as fast as the pipeline takes them; the ones in `damaged` come out unreadable.
class CountingSource final : public SourceStage {
 public:
  explicit CountingSource(std::int64_t count, std::vector<std::int64_t> damaged = {})
      : count_(count), damaged_(std::move(damaged)) {}
  std::string_view name() const override { return "read"; }
  Produced produce(FrameSlot& slot) override {
    if (interrupted_ || next_ >= count_) return Produced::kEnd;
    slot.frame.frame_index = next_++;
    slot.frame.t_ns = slot.frame.frame_index * 1000;
    const bool damaged = std::find(damaged_.begin(), damaged_.end(), slot.frame.frame_index) != damaged_.end();
    return damaged ? Produced::kDamaged : Produced::kFrame;
  }
  void interrupt() override { interrupted_ = true; }
  std::int64_t produced() const { return next_; }

 private:
  std::int64_t count_;
  std::vector<std::int64_t> damaged_;
  std::int64_t next_ = 0;
  std::atomic<bool> interrupted_{false};
};

// Spins for a random time up to max_us per frame (deterministic per seed), optionally throws at one
// frame, optionally may be skipped by the live policy.
class DelayStage final : public Stage {
 public:
  DelayStage(std::string name, int max_us, unsigned seed, bool can_skip = false, std::int64_t throw_at = -1)
      : name_(std::move(name)), max_us_(max_us), random_(seed), can_skip_(can_skip), throw_at_(throw_at) {}
  std::string_view name() const override { return name_; }
  bool canSkipInput() const override { return can_skip_; }
  void process(FrameSlot& slot, Emitter& out) override {
    if (slot.frameIndex() == throw_at_) throw std::runtime_error("planted failure");
    const int us = max_us_ > 0 ? static_cast<int>(random_() % static_cast<unsigned>(max_us_ + 1)) : 0;
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(us);
    while (std::chrono::steady_clock::now() < until) {
    }
    ++seen_;
    out.forward(slot);
  }
  std::int64_t seen() const { return seen_; }

 private:
  std::string name_;
  int max_us_;
  std::minstd_rand random_;
  bool can_skip_;
  std::int64_t throw_at_;
  std::int64_t seen_ = 0;
};

// A stage that does part of each frame on a StageHelper, as the frontend does with its right camera.
class HelperStage final : public Stage {
 public:
  explicit HelperStage(std::string name) : name_(std::move(name)) {}
  std::string_view name() const override { return name_; }
  bool usesHelper() const override { return true; }
  const StageHelper* helper() const override { return helper_.get(); }
  void start(const StageContext& context) override {
    helper_ = std::make_unique<StageHelper>(
        "voca-test-helper", [] { spinFor(std::chrono::microseconds(150)); }, context.helperCore(name()));
  }
  void process(FrameSlot& slot, Emitter& out) override {
    helper_->request();
    spinFor(std::chrono::microseconds(100));
    helper_->wait();
    out.forward(slot);
  }

 private:
  static void spinFor(std::chrono::microseconds duration) {
    const auto until = std::chrono::steady_clock::now() + duration;
    while (std::chrono::steady_clock::now() < until) {
    }
  }
  std::string name_;
  std::unique_ptr<StageHelper> helper_;
};

// The `--profile` table of a report, as printLatencyReport writes it.
std::string latencyReportText(const RunReport& report) {
  char* buffer = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  printLatencyReport(report, out);
  std::fclose(out);
  std::string text(buffer, size);
  std::free(buffer);
  return text;
}

// The lowest core this process may run on.
int firstAllowedCore() {
  cpu_set_t set;
  CPU_ZERO(&set);
  REQUIRE(sched_getaffinity(0, sizeof(set), &set) == 0);
  for (int core = 0; core < CPU_SETSIZE; ++core) {
    if (CPU_ISSET(core, &set)) return core;
  }
  FAIL("no core in the affinity mask");
  return -1;
}

// Records the frame order it sees.
class RecordingSink final : public Stage {
 public:
  std::string_view name() const override { return "write"; }
  void process(FrameSlot& slot, Emitter& out) override {
    indices.push_back(slot.frameIndex());
    out.forward(slot);
  }
  void finish(Emitter& /*out*/) override { finished = true; }
  std::vector<std::int64_t> indices;
  bool finished = false;
};

// Keeps as many slots as the runner allows and forwards the oldest beyond that, like a decoder
// stage waiting for pictures held back inside its decoder.
class HoldingStage final : public Stage {
 public:
  std::string_view name() const override { return "decode"; }
  void start(const StageContext& context) override { limit = context.maxHeldSlots(); }
  void process(FrameSlot& slot, Emitter& out) override {
    held_.push_back(&slot);
    max_held = std::max(max_held, static_cast<int>(held_.size()) - 1);  // kept after the call
    while (static_cast<int>(held_.size()) > limit) {
      out.forward(*held_.front());
      held_.erase(held_.begin());
    }
  }
  void finish(Emitter& out) override {
    for (FrameSlot* slot : held_) out.forward(*slot);
    held_.clear();
  }
  int limit = -1;
  int max_held = 0;

 private:
  std::vector<FrameSlot*> held_;
};

bool strictlyIncreasing(const std::vector<std::int64_t>& v) {
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (v[i] <= v[i - 1]) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("pipeline: offline policy keeps all 20000 frames in order, in every thread layout") {
  constexpr std::int64_t kFrames = 20000;
  for (const int threads : {1, 2, 0}) {
    CountingSource source(kFrames);
    DelayStage decode("decode", 20, 1), frontend("frontend", 30, 2, true), backend("backend", 30, 3);
    RecordingSink sink;
    PipelineOptions options;
    options.threads = threads;
    Pipeline pipeline(source, {&decode, &frontend, &backend, &sink}, options);
    const RunReport report = pipeline.run();
    INFO("threads option " << threads << " -> " << report.threads << " threads");
    CHECK(report.threads == (threads == 0 ? 5 : threads));
    CHECK_FALSE(report.error);
    CHECK(report.produced == kFrames);
    CHECK(report.completed == kFrames);
    CHECK(report.dropped == 0);
    REQUIRE(sink.indices.size() == static_cast<std::size_t>(kFrames));
    CHECK(strictlyIncreasing(sink.indices));
    CHECK(sink.finished);
    CHECK(report.end_to_end.count() == kFrames);
    for (const StageReport& s : report.stages) CHECK(s.service.count() == kFrames);
  }
}

TEST_CASE("pipeline: a stage holding as many slots as the runner allows never starves the source") {
  // A stage may hold maxHeldSlots() slots between calls; the source must still get one to bring the
  // frame that lets the oldest go (holding the whole pool is the hang this guards against).
  constexpr std::int64_t kFrames = 2000;
  for (const int pool : {1, 2, 4, 8}) {
    for (const int threads : {1, 0}) {
      for (const bool live : {false, true}) {
        CAPTURE(pool);
        CAPTURE(threads);
        CAPTURE(live);
        CountingSource source(kFrames);
        HoldingStage hold;
        DelayStage frontend("frontend", 0, 1, true);
        RecordingSink sink;
        PipelineOptions options;
        options.threads = threads;
        options.live_policy = live;
        options.pool_size = pool;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        options.stop_requested = [deadline] { return std::chrono::steady_clock::now() > deadline; };
        Pipeline pipeline(source, {&hold, &frontend, &sink}, options);
        const RunReport report = pipeline.run();
        CHECK_FALSE(report.stopped);
        CHECK_FALSE(report.error);
        CHECK(hold.limit == pool - 1);
        CHECK(hold.max_held == pool - 1);
        CHECK(report.produced == kFrames);
        CHECK(report.completed + report.dropped == kFrames);
        CHECK(strictlyIncreasing(sink.indices));
        if (!live) CHECK(report.completed == kFrames);
      }
    }
  }
}

TEST_CASE("pipeline: live policy drops only in front of a skippable stage, and every drop is counted") {
  constexpr std::int64_t kFrames = 20000;
  // A slow frontend behind a fast source: most frames must be dropped, the rest arrive in order.
  CountingSource source(kFrames);
  DelayStage decode("decode", 0, 1), frontend("frontend", 60, 2, true), backend("backend", 10, 3);
  RecordingSink sink;
  PipelineOptions options;
  options.threads = 0;
  options.live_policy = true;
  Pipeline pipeline(source, {&decode, &frontend, &backend, &sink}, options);
  const RunReport report = pipeline.run();
  CHECK_FALSE(report.error);
  CHECK(report.produced == kFrames);
  CHECK(decode.seen() == kFrames);  // a decoder sees every frame
  CHECK(report.dropped > 0);
  CHECK(report.dropped == kFrames - static_cast<std::int64_t>(sink.indices.size()));
  CHECK(report.completed + report.dropped == kFrames);
  CHECK(strictlyIncreasing(sink.indices));
  // Drops are recorded at the frontend, each with the index of a frame the sink never saw.
  CHECK(report.stages[2].dropped == report.dropped);
  std::vector<bool> seen(kFrames, false);
  for (const std::int64_t i : sink.indices) seen[static_cast<std::size_t>(i)] = true;
  std::int64_t missing = 0;
  for (const bool s : seen) missing += s ? 0 : 1;
  CHECK(missing == report.dropped);
  REQUIRE(report.released.size() == static_cast<std::size_t>(report.dropped));
  for (const ReleasedFrame& f : report.released) {
    CHECK(f.reason == ReleaseReason::kDropped);
    CHECK_FALSE(seen[static_cast<std::size_t>(f.frame_index)]);
  }
}

TEST_CASE("pipeline: frames the source could not read are released as damaged at the read stage and listed") {
  constexpr std::int64_t kFrames = 200;
  const std::vector<std::int64_t> damaged = {0, 57, 58, 199};  // first, a run of two, last
  for (const int threads : {1, 0}) {
    INFO("threads " << threads);
    CountingSource source(kFrames, damaged);
    DelayStage decode("decode", 5, 1), frontend("frontend", 5, 2, true);
    RecordingSink sink;
    PipelineOptions options;
    options.threads = threads;
    Pipeline pipeline(source, {&decode, &frontend, &sink}, options);
    const RunReport report = pipeline.run();
    CHECK_FALSE(report.error);
    CHECK(report.produced == kFrames);
    CHECK(report.damaged == static_cast<std::int64_t>(damaged.size()));
    CHECK(report.stages[0].damaged == report.damaged);
    CHECK(report.completed == kFrames - report.damaged);
    // No later stage saw them; every other frame went through in order.
    CHECK(decode.seen() == kFrames - report.damaged);
    REQUIRE(sink.indices.size() == static_cast<std::size_t>(report.completed));
    CHECK(strictlyIncreasing(sink.indices));
    for (const std::int64_t i : damaged) {
      CHECK(std::find(sink.indices.begin(), sink.indices.end(), i) == sink.indices.end());
    }
    REQUIRE(report.released.size() == damaged.size());
    for (std::size_t k = 0; k < damaged.size(); ++k) {
      CHECK(report.released[k].frame_index == damaged[k]);
      CHECK(report.released[k].reason == ReleaseReason::kDamaged);
      CHECK(report.released[k].stage == 0);
    }
  }
}

TEST_CASE("pipeline: a throwing stage stops the run with its name and frame, finishes earlier frames, never hangs") {
  for (const int threads : {1, 0}) {
    CountingSource source(100000);
    DelayStage decode("decode", 5, 1), frontend("frontend", 5, 2, false, 137), backend("backend", 5, 3);
    RecordingSink sink;
    PipelineOptions options;
    options.threads = threads;
    Pipeline pipeline(source, {&decode, &frontend, &backend, &sink}, options);
    const RunReport report = pipeline.run();
    INFO("threads " << threads);
    REQUIRE(report.error);
    CHECK(report.error->stage == "frontend");
    CHECK(report.error->frame_index == 137);
    CHECK(report.error->message == "planted failure");
    // Every frame before the failure passed every stage; none after it reached the sink.
    REQUIRE(sink.indices.size() == 137);
    CHECK(sink.indices.back() == 136);
    CHECK(strictlyIncreasing(sink.indices));
    CHECK(sink.finished);
    CHECK(source.produced() < 100000);
  }
}

TEST_CASE("pipeline: a stop request drains the queues and reports it") {
  CountingSource source(1000000);
  DelayStage decode("decode", 10, 1), frontend("frontend", 10, 2, true), backend("backend", 10, 3);
  RecordingSink sink;
  PipelineOptions options;
  std::atomic<int> polls{0};
  options.stop_requested = [&] { return polls.fetch_add(1) > 200; };
  Pipeline pipeline(source, {&decode, &frontend, &backend, &sink}, options);
  const RunReport report = pipeline.run();
  CHECK(report.stopped);
  CHECK_FALSE(report.error);
  CHECK(report.produced < 1000000);
  // Everything the source produced went through (offline policy: no drops on the way out).
  CHECK(report.completed == report.produced);
  CHECK(static_cast<std::int64_t>(sink.indices.size()) == report.produced);
}

TEST_CASE("pipeline: thread layouts and pins are checked") {
  CountingSource source(10);
  DelayStage decode("decode", 0, 1), frontend("frontend", 0, 2), backend("backend", 0, 3);
  RecordingSink sink;
  PipelineOptions options;
  options.threads = 2;
  const auto layout = Pipeline(source, {&decode, &frontend, &backend, &sink}, options).threadOfStage();
  // Equal costs over 5 stages in 2 threads: contiguous runs, the source's first.
  REQUIRE(layout.size() == 5);
  CHECK(layout.front() == 0);
  CHECK(layout.back() == 1);
  CHECK(std::is_sorted(layout.begin(), layout.end()));

  options.pins = {{"tracker", 0}};
  test::expectError(test::inputErrorOf([&] {
                      Pipeline(source, {&decode, &frontend, &backend, &sink}, options);
                    }),
                    "no stage named \"tracker\"");
  options.threads = 1;
  options.pins = {{"decode", 0}, {"backend", 1}};
  test::expectError(test::inputErrorOf([&] {
                      Pipeline(source, {&decode, &frontend, &backend, &sink}, options);
                    }),
                    "shares a thread");
  CHECK(parseStagePins("decode:0,frontend:0,backend:1") ==
        std::vector<std::pair<std::string, int>>{{"decode", 0}, {"frontend", 0}, {"backend", 1}});
  test::expectError(test::inputErrorOf([] { parseStagePins("decode=0"); }), "stage:core");
  test::expectError(test::inputErrorOf([] { parseStagePins("decode:-1"); }), "stage:core");
  test::expectError(test::inputErrorOf([] { parseStagePins(":3"); }), "stage:core");
}

TEST_CASE("pipeline: a pin the OS refuses is one warning and the run goes on") {
  CountingSource source(50);
  DelayStage frontend("frontend", 0, 2);
  RecordingSink sink;
  PipelineOptions options;
  options.pins = {{"frontend", 4095}};  // no machine this runs on has that core
  Pipeline pipeline(source, {&frontend, &sink}, options);
  const RunReport report = pipeline.run();
  CHECK(report.completed == 50);
  REQUIRE(report.warnings.size() == 1);
  CHECK(report.warnings[0].find("core 4095") != std::string::npos);
}

TEST_CASE("stage helper: runs its task once per request on its own thread, sees the caller's writes, rethrows") {
  // The task reads what the caller wrote before request() and writes what the caller reads after
  // wait(), with no atomics of its own: the handoff orders them (a missed order shows as a wrong sum).
  std::vector<std::int64_t> input(64), output(64);
  std::thread::id task_thread;
  int runs = 0;
  bool fail = false;
  StageHelper helper("voca-test", [&] {
    task_thread = std::this_thread::get_id();
    ++runs;
    if (fail) throw std::runtime_error("task failed on purpose");
    for (std::size_t i = 0; i < input.size(); ++i) output[i] = 2 * input[i];
  });
  std::int64_t checked = 0;
  for (std::int64_t round = 1; round <= 20000; ++round) {
    for (std::size_t i = 0; i < input.size(); ++i) input[i] = round + static_cast<std::int64_t>(i);
    helper.request();
    helper.wait();
    for (std::size_t i = 0; i < output.size(); ++i) checked += output[i] == 2 * (round + static_cast<std::int64_t>(i));
  }
  CHECK(runs == 20000);
  CHECK(checked == 20000 * 64);
  CHECK(task_thread != std::this_thread::get_id());
  fail = true;
  helper.request();
  CHECK_THROWS_WITH_AS(helper.wait(), "task failed on purpose", std::runtime_error);
  // The helper goes on after a failure.
  fail = false;
  helper.request();
  helper.wait();
  CHECK(runs == 20002);
  CHECK(output[0] == 2 * (20000 + 0));
}

TEST_CASE("stage helper: destroyed with a request outstanding, it finishes the task first") {
  std::atomic<int> finished{0};
  {
    StageHelper helper("voca-test", [&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      finished.fetch_add(1);
    });
    helper.request();
  }
  CHECK(finished.load() == 1);
}

TEST_CASE("stage helper: times each run on its own thread's clock; a core it cannot have is a warning") {
  StageHelper helper("voca-test", [] {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(3);
    while (std::chrono::steady_clock::now() < until) {
    }
  });
  CHECK(helper.pinWarning().empty());
  helper.request();
  helper.wait();
  const StageTiming& run = helper.lastRun();
  CHECK(run.end_ns - run.start_ns >= 3'000'000);
  CHECK(run.cpu_ns > 0);
  CHECK(run.cpu_ns <= run.end_ns - run.start_ns + 1'000'000);  // the thread's CPU clock, not the process's
  StageHelper pinned(
      "voca-test", [] {}, firstAllowedCore());
  CHECK(pinned.pinWarning().empty());
  StageHelper refused(
      "voca-test", [] {}, 4095);  // no machine this runs on has that core
  CHECK(refused.pinWarning().find("core 4095") != std::string::npos);
  refused.request();  // and it still works, where it was created
  refused.wait();
  CHECK(refused.lastRun().end_ns >= refused.lastRun().start_ns);
}

TEST_CASE("pipeline: a stage's helper thread gets its own trace track and profile row, and a pin of its own") {
  test::ScratchDir dir("pipeline-helper-trace");
  CountingSource source(200);
  DelayStage decode("decode", 30, 1);
  HelperStage frontend("frontend");
  RecordingSink sink;
  PipelineOptions options;
  options.trace_path = dir / "trace.json";
  const int core = firstAllowedCore();
  options.pins = {{"frontend.helper", core}};
  Pipeline pipeline(source, {&decode, &frontend, &sink}, options);
  const RunReport report = pipeline.run();
  REQUIRE(report.completed == 200);
  CHECK(report.warnings.empty());
  REQUIRE(report.stages.size() == 4);
  const StageReport& stage = report.stages[2];
  CHECK(stage.helper_service.count() == 200);
  CHECK(stage.helper_cpu.count() == 200);
  CHECK(stage.helper_service.quantileNs(0.5) >= 150'000);
  CHECK(stage.helper_core == core);
  CHECK(stage.core == -1);  // the stage's own thread is not pinned by its helper's pin
  CHECK(report.stages[1].helper_service.count() == 0);

  // The trace reads back to the same helper rows, and every helper slice lies inside its frame's
  // stage slice on a track of its own.
  const RunReport read = readTraceReport(dir / "trace.json");
  CHECK(read.stages[2].helper_core == core);
  for (const double q : {0.5, 0.99, 1.0}) {
    CHECK(read.stages[2].helper_service.quantileNs(q) == stage.helper_service.quantileNs(q));
    CHECK(read.stages[2].helper_cpu.quantileNs(q) == stage.helper_cpu.quantileNs(q));
  }
  CHECK(latencyReportText(read).find("+ helper") != std::string::npos);
  CHECK(latencyReportText(read) == latencyReportText(report));

  std::ifstream in(dir / "trace.json");
  const nlohmann::json events = nlohmann::json::parse(in);
  std::map<std::int64_t, std::pair<double, double>> stage_span;  // frame -> frontend slice [ts, ts + dur]
  std::vector<nlohmann::json> helper_slices;
  int stage_tid = -1, helper_names = 0;
  for (const nlohmann::json& e : events) {
    if (e.value("cat", "") == "stage" && e.value("name", "") == "frontend") {
      stage_tid = e.at("tid").get<int>();
      const double ts = e.at("ts").get<double>();
      stage_span[e.at("args").at("frame").get<std::int64_t>()] = {ts, ts + e.at("dur").get<double>()};
    }
    if (e.value("cat", "") == "helper") helper_slices.push_back(e);
    if (e.value("name", "") == "thread_name" &&
        e.at("args").at("name").get<std::string>() == "thread 2 helper: frontend")
      ++helper_names;
  }
  CHECK(helper_names == 1);
  REQUIRE(helper_slices.size() == 200);
  int inside = 0;
  for (const nlohmann::json& h : helper_slices) {
    CHECK(h.at("tid").get<int>() != stage_tid);
    const auto [begin, end] = stage_span.at(h.at("args").at("frame").get<std::int64_t>());
    const double ts = h.at("ts").get<double>();
    inside += ts >= begin && ts + h.at("dur").get<double>() <= end;
  }
  CHECK(inside == 200);

  // A helper pin names a stage that runs one.
  CountingSource again(5);
  options.trace_path.clear();
  options.pins = {{"decode.helper", core}};
  test::expectError(test::inputErrorOf([&] {
                      Pipeline(again, {&decode, &frontend, &sink}, options);
                    }),
                    "the decode stage runs no helper thread");
  options.pins = {{"tracker.helper", core}};
  test::expectError(test::inputErrorOf([&] {
                      Pipeline(again, {&decode, &frontend, &sink}, options);
                    }),
                    "(stages: read, decode, frontend, frontend.helper, write)");
}

TEST_CASE("latency histogram: exact below 128 ns, within 0.8 % above, exact extremes") {
  LatencyHistogram h;
  CHECK(h.quantileNs(0.5) == 0);
  for (std::int64_t v = 1; v <= 100; ++v) h.record(v);
  CHECK(h.quantileNs(0.0) == 1);
  CHECK(h.quantileNs(1.0) == 100);
  CHECK(h.quantileNs(0.5) == 51);  // rank round(0.5 * 99) = 50 -> the 51st value, exact below 128 ns
  LatencyHistogram big;
  std::minstd_rand random(7);
  std::vector<std::int64_t> values;
  for (int i = 0; i < 10001; ++i) {
    values.push_back(1000 + static_cast<std::int64_t>(random() % 50'000'000));
    big.record(values.back());
  }
  std::sort(values.begin(), values.end());
  for (const double q : {0.1, 0.5, 0.9, 0.99}) {
    const double exact = static_cast<double>(values[static_cast<std::size_t>(std::llround(q * 10000))]);
    CHECK(std::abs(static_cast<double>(big.quantileNs(q)) - exact) <= exact / 128.0 + 1.0);
  }
  CHECK(big.maxNs() == values.back());
  LatencyHistogram merged;
  merged.merge(h);
  merged.merge(big);
  CHECK(merged.count() == 10101);
  CHECK(merged.maxNs() == values.back());
}

TEST_CASE("pipeline: the Chrome trace reads back to the run's own latency statistics") {
  test::ScratchDir dir("pipeline-trace");
  CountingSource source(300);
  DelayStage decode("decode", 30, 1), frontend("frontend", 50, 2, true), backend("backend", 40, 3);
  RecordingSink sink;
  PipelineOptions options;
  options.trace_path = dir / "trace.json";
  Pipeline pipeline(source, {&decode, &frontend, &backend, &sink}, options);
  const RunReport report = pipeline.run();
  REQUIRE(report.completed == 300);
  bool complete = false;
  const RunReport read = readTraceReport(dir / "trace.json", &complete);
  CHECK(complete);
  CHECK(read.completed == 300);
  CHECK(read.threads == report.threads);
  REQUIRE(read.stages.size() == report.stages.size());
  for (std::size_t k = 0; k < read.stages.size(); ++k) {
    INFO("stage " << report.stages[k].name);
    CHECK(read.stages[k].name == report.stages[k].name);
    CHECK(read.stages[k].queue_high_water == report.stages[k].queue_high_water);
    for (const double q : {0.5, 0.9, 0.99, 1.0}) {
      CHECK(read.stages[k].service.quantileNs(q) == report.stages[k].service.quantileNs(q));
      CHECK(read.stages[k].wait.quantileNs(q) == report.stages[k].wait.quantileNs(q));
      CHECK(read.stages[k].cpu.quantileNs(q) == report.stages[k].cpu.quantileNs(q));
    }
  }
  CHECK(read.end_to_end.quantileNs(0.99) == report.end_to_end.quantileNs(0.99));
  // The printed tables are the same text.
  CHECK(latencyReportText(read) == latencyReportText(report));

  // A trace cut off mid-run (the process was killed) still reads.
  std::string text;
  {
    std::ifstream in(dir / "trace.json");
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::size_t summary = text.find("\"cat\":\"summary\"");
  REQUIRE(summary != std::string::npos);
  const std::size_t cut = text.rfind(",\n{", summary);
  test::writeText(dir / "cut.json", text.substr(0, cut));
  const RunReport cut_report = readTraceReport(dir / "cut.json", &complete);
  CHECK_FALSE(complete);
  CHECK(cut_report.completed == 300);
  // Without the summary, the threads the stage events ran on (one used to be printed, whatever ran).
  REQUIRE(report.threads > 1);
  CHECK(cut_report.threads == report.threads);
  // Cut in the middle of an event (killed during a write, or a full disk): the whole events before it
  // read. Frame 100's events begin at its first stage slice; cutting inside that slice leaves 100 frames.
  const std::size_t frame100 = text.find("\"frame\":100,\"stage\":0");
  REQUIRE(frame100 != std::string::npos);
  test::writeText(dir / "cut_mid_event.json", text.substr(0, frame100 + 5));
  CHECK(readTraceReport(dir / "cut_mid_event.json").completed == 100);
  test::writeText(dir / "bad.json", "{\"not\": \"a trace\"}");
  test::expectError(test::inputErrorOf([&] { readTraceReport(dir / "bad.json"); }), "not a Chrome trace");
  // A stage index that is negative, huge or fractional is a malformed event, not an index (-1 crashed,
  // 1e9 tried to allocate a billion stages).
  for (const char* stage : {"-1", "1000000000", "1.5", "8"}) {
    CAPTURE(stage);
    test::writeText(dir / "stage.json",
                    std::string(R"([{"name":"read","cat":"stage","ph":"X","pid":1,"tid":1,"ts":0,"dur":1,)") +
                        R"("args":{"frame":0,"stage":)" + stage + R"(,"cpu_us":1}}])");
    test::expectError(test::inputErrorOf([&] { readTraceReport(dir / "stage.json"); }),
                      std::string("malformed trace event (stage ") + stage);
  }
}
