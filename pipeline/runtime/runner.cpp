#include "pipeline/runtime/runner.h"

#include <fmt/core.h>

#include <concurrentqueue/concurrentqueue.h>  // defines what lightweightsemaphore.h expects
#include <concurrentqueue/lightweightsemaphore.h>
#include <readerwriterqueue/readerwritercircularbuffer.h>
#include <algorithm>
#include <atomic>
#include <charconv>
#include <climits>
#include <exception>
#include <limits>
#include <memory>
#include <thread>

#include "pipeline/runtime/chrome_trace.h"
#include "pipeline/runtime/stage_helper.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

using SlotQueue = moodycamel::BlockingReaderWriterCircularBuffer<FrameSlot*>;
constexpr std::int64_t kPollUs = 20000;  // how often a waiting thread looks at the stop and abort flags
constexpr std::size_t kMaxReleasedRecords = 65536;

// Splits stage costs into `groups` runs of consecutive stages, minimising the largest run's cost.
std::vector<int> balancedGroups(const std::vector<int>& costs, int groups) {
  const int n = static_cast<int>(costs.size());
  groups = std::clamp(groups, 1, n);
  // best[g][i]: the smallest possible maximum cost of splitting stages [0, i) into g runs.
  const int kInf = INT_MAX;
  std::vector<std::vector<int>> best(static_cast<std::size_t>(groups) + 1,
                                     std::vector<int>(static_cast<std::size_t>(n) + 1, kInf));
  std::vector<std::vector<int>> cut(best.size(), std::vector<int>(static_cast<std::size_t>(n) + 1, 0));
  best[0][0] = 0;
  for (int g = 1; g <= groups; ++g) {
    for (int i = g; i <= n; ++i) {
      int run = 0;
      for (int j = i - 1; j >= g - 1; --j) {
        run += costs[static_cast<std::size_t>(j)];
        const int previous = best[static_cast<std::size_t>(g - 1)][static_cast<std::size_t>(j)];
        if (previous == kInf) continue;
        const int cost = std::max(previous, run);
        if (cost < best[static_cast<std::size_t>(g)][static_cast<std::size_t>(i)]) {
          best[static_cast<std::size_t>(g)][static_cast<std::size_t>(i)] = cost;
          cut[static_cast<std::size_t>(g)][static_cast<std::size_t>(i)] = j;
        }
      }
    }
  }
  std::vector<int> group_of(static_cast<std::size_t>(n), 0);
  int end = n;
  for (int g = groups; g >= 1; --g) {
    const int begin = cut[static_cast<std::size_t>(g)][static_cast<std::size_t>(end)];
    for (int k = begin; k < end; ++k) group_of[static_cast<std::size_t>(k)] = g - 1;
    end = begin;
  }
  return group_of;
}

}  // namespace

struct Pipeline::Impl final : StageContext {
  struct Group {
    int first = 0, last = 0;  // stage positions, inclusive
    int core = -1;
    std::unique_ptr<SlotQueue> input;      // null for the source's group
    std::unique_ptr<SlotQueue> free_ring;  // slots this group released, for the source to reuse
    std::vector<ReleasedFrame> released;   // this group's drops and damaged frames
    std::thread thread;
  };
  struct StageEmitter final : Emitter {
    Impl* impl = nullptr;
    int stage = 0;
    // The slot the stage is processing, and whether it already handed it on: once handed on, another
    // thread owns it and this one must not read it again (not even to name its frame in an error).
    const FrameSlot* current = nullptr;
    bool current_handed_on = false;
    void forward(FrameSlot& slot) override {
      if (&slot == current) current_handed_on = true;
      impl->afterStage(stage, slot);
    }
    void release(FrameSlot& slot, ReleaseReason reason) override {
      if (&slot == current) current_handed_on = true;
      impl->release(stage, slot, reason);
    }
  };

  SourceStage& source;
  std::vector<Stage*> stages;  // position k + 1 is stages[k]; position 0 is the source
  PipelineOptions options;
  std::vector<int> group_of;
  std::vector<Group> groups;
  std::vector<std::unique_ptr<FrameSlot>> pool;
  moodycamel::LightweightSemaphore free_count;
  std::vector<StageEmitter> emitters;
  std::vector<StageReport> reports;
  std::vector<std::string> names;
  std::vector<int> helper_cores;      // per stage position: the core its helper thread is pinned to, -1: none
  std::atomic<int> failed_stage{-1};  // the furthest stage that failed; -1: none
  // Drop and damage records left to take, shared by the groups: usually one group does all the
  // dropping (the one with the frontend), so an even split per group would cut its list short.
  std::atomic<std::int64_t> release_records_left{static_cast<std::int64_t>(kMaxReleasedRecords)};
  std::atomic<bool> source_finished{false};
  // Every drop and damaged frame so far, for the sinks (FrameSlot::dropped_so_far).
  std::atomic<std::int64_t> dropped_total{0};
  std::atomic<std::int64_t> damaged_total{0};
  std::optional<StageError> error;  // guarded by error_claimed
  std::atomic<bool> error_claimed{false};
  std::unique_ptr<ChromeTraceWriter> trace;
  RunReport report;
  std::int64_t sequence = 0;
  std::vector<std::string> warnings;  // written before the threads start and after they end

  Impl(SourceStage& source_stage, std::vector<Stage*> chain, PipelineOptions opts)
      : source(source_stage), stages(std::move(chain)), options(std::move(opts)) {}

  int numStages() const { return static_cast<int>(stages.size()) + 1; }
  int lastStage() const { return numStages() - 1; }
  bool aborting() const override { return failed_stage.load(std::memory_order_acquire) >= 0; }
  int maxHeldSlots() const override { return std::max(static_cast<int>(pool.size()) - 1, 0); }
  int helperCore(std::string_view stage) const override {
    const auto it = std::find(names.begin(), names.end(), stage);
    return it == names.end() ? -1 : helper_cores[static_cast<std::size_t>(it - names.begin())];
  }

  // frame_index: the frame the stage failed on, -1 for none.
  void fail(int stage, std::int64_t frame_index, const std::string& message) {
    if (!error_claimed.exchange(true)) {
      error = StageError{names[static_cast<std::size_t>(stage)], frame_index, message};
    }
    int current = failed_stage.load();
    while (current < stage && !failed_stage.compare_exchange_weak(current, stage)) {
    }
    source.interrupt();
  }

  // ---- slots ----

  FrameSlot* acquire() {
    for (;;) {
      if (free_count.wait(kPollUs)) {
        for (;;) {
          for (Group& group : groups) {
            FrameSlot* slot = nullptr;
            if (group.free_ring->try_dequeue(slot)) return slot;
          }
        }
      }
      if (stopNow()) return nullptr;
    }
  }

  void releaseToFree(int stage, FrameSlot& slot) {
    slot.owner_stage = -1;
    groups[static_cast<std::size_t>(group_of[static_cast<std::size_t>(stage)])].free_ring->wait_enqueue(&slot);
    free_count.signal();
  }

  void release(int stage, FrameSlot& slot, ReleaseReason reason) {
    StageReport& r = reports[static_cast<std::size_t>(stage)];
    if (reason == ReleaseReason::kDropped) {
      ++r.dropped;
      dropped_total.fetch_add(1, std::memory_order_relaxed);
    }
    if (reason == ReleaseReason::kDamaged) {
      ++r.damaged;
      damaged_total.fetch_add(1, std::memory_order_relaxed);
    }
    if (reason == ReleaseReason::kDropped || reason == ReleaseReason::kDamaged) {
      auto& list = groups[static_cast<std::size_t>(group_of[static_cast<std::size_t>(stage)])].released;
      if (list.size() < list.capacity() && release_records_left.fetch_sub(1, std::memory_order_relaxed) > 0) {
        list.push_back({slot.frameIndex(), platform::monotonicNs(), stage, reason});
      }
    }
    releaseToFree(stage, slot);
  }

  // ---- running stages ----

  bool stopNow() const { return aborting() || (options.stop_requested && options.stop_requested()); }

  void runStage(int stage, FrameSlot& slot) {
    const int failed = failed_stage.load(std::memory_order_acquire);
    if (failed >= 0 && stage <= failed) {
      release(stage, slot, ReleaseReason::kAborted);
      return;
    }
    StageTiming& t = slot.timing[static_cast<std::size_t>(stage)];
    t.start_ns = platform::monotonicNs();
    t.cpu_start_ns = platform::threadCpuNs();
    slot.owner_stage = stage;
    if (stage == lastStage()) {
      slot.dropped_so_far = dropped_total.load(std::memory_order_relaxed);
      slot.damaged_so_far = damaged_total.load(std::memory_order_relaxed);
    }
    StageEmitter& emitter = emitters[static_cast<std::size_t>(stage)];
    const std::int64_t frame_index = slot.frameIndex();
    emitter.current = &slot;
    emitter.current_handed_on = false;
    try {
      stages[static_cast<std::size_t>(stage - 1)]->process(slot, emitter);
    } catch (const std::exception& e) {
      fail(stage, frame_index, e.what());
      if (!emitter.current_handed_on) release(stage, slot, ReleaseReason::kAborted);
    }
    emitter.current = nullptr;
  }

  // A stage forwarded the slot: stamp its end and hand the slot on.
  void afterStage(int stage, FrameSlot& slot) {
    StageTiming& t = slot.timing[static_cast<std::size_t>(stage)];
    t.end_ns = platform::monotonicNs();
    t.cpu_ns = platform::threadCpuNs() - t.cpu_start_ns;
    if (stage > 0) {
      if (const StageHelper* helper = stages[static_cast<std::size_t>(stage - 1)]->helper()) {
        slot.helper_timing = helper->lastRun();
        slot.helper_stage = stage;
      }
    }
    ++reports[static_cast<std::size_t>(stage)].forwarded;
    slot.owner_stage = -1;
    if (stage == lastStage()) {
      complete(slot);
      return;
    }
    const int next = stage + 1;
    const int group = group_of[static_cast<std::size_t>(next)];
    if (group == group_of[static_cast<std::size_t>(stage)]) {
      runStage(next, slot);
      return;
    }
    SlotQueue& queue = *groups[static_cast<std::size_t>(group)].input;
    queue.wait_enqueue(&slot);
    StageReport& r = reports[static_cast<std::size_t>(next)];
    r.queue_high_water = std::max(r.queue_high_water, queue.size_approx());
  }

  void complete(FrameSlot& slot) {
    for (int k = 0; k < numStages(); ++k) {
      const StageTiming& t = slot.timing[static_cast<std::size_t>(k)];
      StageReport& r = reports[static_cast<std::size_t>(k)];
      r.service.record(t.end_ns - t.start_ns);
      r.cpu.record(t.cpu_ns);
      if (k > 0) r.wait.record(t.start_ns - slot.timing[static_cast<std::size_t>(k - 1)].end_ns);
      if (slot.helper_stage == k) {
        r.helper_service.record(slot.helper_timing.end_ns - slot.helper_timing.start_ns);
        r.helper_cpu.record(slot.helper_timing.cpu_ns);
      }
    }
    report.end_to_end.record(slot.timing[static_cast<std::size_t>(lastStage())].end_ns - slot.arrival_ns);
    ++report.completed;
    if (trace) trace->frame(slot, names, group_of);
    releaseToFree(lastStage(), slot);
  }

  void finishGroup(Group& group) {
    for (int k = std::max(group.first, 1); k <= group.last; ++k) {
      try {
        stages[static_cast<std::size_t>(k - 1)]->finish(emitters[static_cast<std::size_t>(k)]);
      } catch (const std::exception& e) {
        fail(k, -1, e.what());
      }
    }
    const std::size_t index = static_cast<std::size_t>(&group - groups.data());
    if (index + 1 < groups.size()) groups[index + 1].input->wait_enqueue(nullptr);
  }

  void startGroup(Group& group, int index) {
    const std::string& first = names[static_cast<std::size_t>(group.first)];
    platform::nameCurrentThread("voca-" + first);
    if (group.core >= 0) {
      const platform::ControlResult pinned = platform::pinCurrentThread(group.core);
      if (!pinned.ok) warn(fmt::format("thread {} ({}): {}", index, first, pinned.message));
    }
    if (options.scheduling != platform::SchedulingPolicy::kOther) {
      const platform::ControlResult scheduled =
          platform::setCurrentThreadScheduling(options.scheduling, options.priority);
      if (!scheduled.ok) warn(scheduled.message);
    }
    for (int k = group.first; k <= group.last; ++k) {
      try {
        if (k == 0) {
          source.start(*this);
        } else {
          Stage& stage = *stages[static_cast<std::size_t>(k - 1)];
          stage.start(*this);
          if (const StageHelper* helper = stage.helper(); helper != nullptr && !helper->pinWarning().empty()) {
            warn(fmt::format("thread {} ({} helper): {}", index, names[static_cast<std::size_t>(k)],
                             helper->pinWarning()));
          }
        }
      } catch (const std::exception& e) {
        fail(k, -1, e.what());
      }
    }
  }

  // Warnings come from several threads at start-up; each is kept once.
  std::atomic<bool> warn_lock{false};
  void warn(const std::string& message) {
    while (warn_lock.exchange(true, std::memory_order_acquire)) {
    }
    if (std::find(warnings.begin(), warnings.end(), message) == warnings.end()) warnings.push_back(message);
    warn_lock.store(false, std::memory_order_release);
  }

  void runSourceGroup(Group& group) {
    startGroup(group, 0);
    while (!stopNow()) {
      FrameSlot* slot = acquire();
      if (slot == nullptr) break;
      StageTiming& t = slot->timing[0];
      t.start_ns = platform::monotonicNs();
      t.cpu_start_ns = platform::threadCpuNs();
      slot->owner_stage = 0;
      slot->arrival_ns = 0;
      slot->helper_stage = -1;
      Produced produced = Produced::kEnd;
      try {
        produced = source.produce(*slot);
      } catch (const std::exception& e) {
        fail(0, -1, e.what());
      }
      if (produced == Produced::kEnd) {
        releaseToFree(0, *slot);
        break;
      }
      slot->sequence = sequence++;
      ++report.produced;
      if (produced == Produced::kDamaged) {
        release(0, *slot, ReleaseReason::kDamaged);
        continue;
      }
      if (slot->arrival_ns == 0) {
        slot->arrival_ns = platform::monotonicNs();
      } else {
        // A paced source waited for the frame's due time: that wait is the recording's rate, not
        // work, so the source's service time starts when the frame became available.
        t.start_ns = std::max(t.start_ns, slot->arrival_ns);
      }
      afterStage(0, *slot);
    }
    source_finished.store(true, std::memory_order_release);
    finishGroup(group);
  }

  void runConsumerGroup(Group& group, int index) {
    startGroup(group, index);
    SlotQueue& queue = *group.input;
    const bool may_drop = options.live_policy && stages[static_cast<std::size_t>(group.first - 1)]->canSkipInput();
    const std::size_t backlog = static_cast<std::size_t>(std::max(options.live_backlog, 0));
    for (;;) {
      FrameSlot* slot = nullptr;
      if (!queue.wait_dequeue_timed(slot, kPollUs)) continue;
      if (slot == nullptr) break;
      bool end = false;
      while (may_drop && queue.size_approx() > backlog) {
        FrameSlot* newer = nullptr;
        if (!queue.try_dequeue(newer)) break;
        if (newer == nullptr) {
          end = true;
          break;
        }
        release(group.first, *slot, ReleaseReason::kDropped);
        slot = newer;
      }
      runStage(group.first, *slot);
      if (end) break;
    }
    finishGroup(group);
  }

  void buildLayout() {
    const int n = numStages();
    names.resize(static_cast<std::size_t>(n));
    names[0] = std::string(source.name());
    std::vector<int> costs(static_cast<std::size_t>(n), 1);
    for (int k = 1; k < n; ++k) {
      names[static_cast<std::size_t>(k)] = std::string(stages[static_cast<std::size_t>(k - 1)]->name());
      costs[static_cast<std::size_t>(k)] = std::max(1, stages[static_cast<std::size_t>(k - 1)]->relativeCost());
    }
    if (options.threads < 0)
      throw InputError(fmt::format("threads: expected 0 (one per stage) or more, got {}", options.threads));
    const int threads = options.threads == 0 ? n : std::min(options.threads, n);
    group_of = balancedGroups(costs, threads);
    groups.resize(static_cast<std::size_t>(group_of.back()) + 1);
    for (int k = 0; k < n; ++k) {
      Group& g = groups[static_cast<std::size_t>(group_of[static_cast<std::size_t>(k)])];
      if (k == 0 || group_of[static_cast<std::size_t>(k - 1)] != group_of[static_cast<std::size_t>(k)]) g.first = k;
      g.last = k;
    }
    helper_cores.assign(static_cast<std::size_t>(n), -1);
    for (const auto& [name, core] : options.pins) {
      // helperPinName() names the helper thread of a stage that runs one.
      const std::string suffix = helperPinName("");
      const bool for_helper = name.size() > suffix.size() && name.ends_with(suffix);
      const std::string stage_name = for_helper ? name.substr(0, name.size() - suffix.size()) : name;
      const auto it = std::find(names.begin(), names.end(), stage_name);
      if (it == names.end()) {
        std::string known;
        for (std::size_t k = 0; k < names.size(); ++k) {
          known += (known.empty() ? "" : ", ") + names[k];
          if (k > 0 && stages[k - 1]->usesHelper()) known += ", " + helperPinName(names[k]);
        }
        throw InputError(fmt::format("pin: no stage named \"{}\" in this pipeline (stages: {})", name, known));
      }
      if (core < 0) throw InputError(fmt::format("pin: {}: core must be 0 or more, got {}", name, core));
      const auto position = static_cast<std::size_t>(it - names.begin());
      if (for_helper) {
        if (position == 0 || !stages[position - 1]->usesHelper()) {
          throw InputError(fmt::format("pin: {}: the {} stage runs no helper thread in this run", name, stage_name));
        }
        helper_cores[position] = core;
        continue;
      }
      Group& g = groups[static_cast<std::size_t>(group_of[static_cast<std::size_t>(it - names.begin())])];
      if (g.core >= 0 && g.core != core) {
        throw InputError(fmt::format(
            "pin: {} shares a thread with other stages pinned to core {}; pin them alike or use more threads", name,
            g.core));
      }
      g.core = core;
    }
  }
};

std::string helperPinName(std::string_view stage) { return std::string(stage) + ".helper"; }

const StageReport* RunReport::stage(std::string_view name) const {
  for (const StageReport& s : stages) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

std::vector<std::pair<std::string, int>> parseStagePins(std::string_view text) {
  std::vector<std::pair<std::string, int>> pins;
  while (!text.empty()) {
    const std::size_t comma = text.find(',');
    const std::string_view entry = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view{} : text.substr(comma + 1);
    const std::size_t colon = entry.find(':');
    int core = -1;
    const std::string_view number = colon == std::string_view::npos ? std::string_view{} : entry.substr(colon + 1);
    const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), core);
    if (colon == 0 || colon == std::string_view::npos || ec != std::errc{} || end != number.data() + number.size() ||
        core < 0) {
      throw InputError(
          fmt::format("--pin: expected stage:core pairs such as decode:0,frontend:0,backend:1, got \"{}\"", entry));
    }
    pins.emplace_back(std::string(entry.substr(0, colon)), core);
  }
  return pins;
}

Pipeline::Pipeline(SourceStage& source, std::vector<Stage*> stages, PipelineOptions options)
    : impl_(std::make_unique<Impl>(source, std::move(stages), std::move(options))) {
  Impl& d = *impl_;
  if (static_cast<int>(d.stages.size()) + 1 > kMaxStages) {
    throw InputError(fmt::format("a pipeline has at most {} stages", kMaxStages));
  }
  d.buildLayout();
  group_of_ = d.group_of;
  const int pool_size = d.options.pool_size > 0 ? d.options.pool_size : (d.options.live_policy ? 4 : 8);
  d.pool.reserve(static_cast<std::size_t>(pool_size));
  for (int i = 0; i < pool_size; ++i) {
    auto slot = std::make_unique<FrameSlot>();
    slot->pool_index = i;
    const SlotShape& shape = d.options.slot_shape;
    if (shape.width > 0 && shape.height > 0) {
      slot->reserve(shape.width, shape.height, shape.max_points, shape.max_landmarks);
    }
    d.pool.push_back(std::move(slot));
  }
  for (std::size_t g = 0; g < d.groups.size(); ++g) {
    Impl::Group& group = d.groups[g];
    // Room for every slot plus the end marker, so enqueueing never waits.
    if (g > 0) group.input = std::make_unique<SlotQueue>(static_cast<std::size_t>(pool_size) + 1);
    group.free_ring = std::make_unique<SlotQueue>(static_cast<std::size_t>(pool_size) + 1);
    group.released.reserve(kMaxReleasedRecords);
  }
  for (auto& slot : d.pool) d.groups[0].free_ring->wait_enqueue(slot.get());
  d.free_count.signal(pool_size);
  d.emitters.resize(static_cast<std::size_t>(d.numStages()));
  d.reports.resize(static_cast<std::size_t>(d.numStages()));
  for (int k = 0; k < d.numStages(); ++k) {
    d.emitters[static_cast<std::size_t>(k)].impl = &d;
    d.emitters[static_cast<std::size_t>(k)].stage = k;
    StageReport& r = d.reports[static_cast<std::size_t>(k)];
    r.name = d.names[static_cast<std::size_t>(k)];
    r.thread = d.group_of[static_cast<std::size_t>(k)];
    r.core = d.groups[static_cast<std::size_t>(r.thread)].core;
    r.helper_core = d.helper_cores[static_cast<std::size_t>(k)];
  }
}

Pipeline::~Pipeline() = default;

bool Pipeline::failed() const { return impl_->aborting(); }

RunReport Pipeline::run() {
  Impl& d = *impl_;
  const std::int64_t start = platform::monotonicNs();
  if (!d.options.trace_path.empty()) {
    d.trace = std::make_unique<ChromeTraceWriter>(d.options.trace_path, start);
    for (std::size_t g = 0; g < d.groups.size(); ++g) {
      std::string stages;
      for (int k = d.groups[g].first; k <= d.groups[g].last; ++k) {
        stages += (stages.empty() ? "" : " + ") + d.names[static_cast<std::size_t>(k)];
      }
      d.trace->threadName(static_cast<int>(g), fmt::format("thread {}: {}", g, stages));
    }
  }
  if (d.options.lock_memory) {
    const platform::ControlResult locked = platform::lockAllMemory();
    if (!locked.ok) d.warnings.push_back(locked.message);
  }
  if (d.groups.size() == 1) {
    d.runSourceGroup(d.groups[0]);
  } else {
    for (std::size_t g = 1; g < d.groups.size(); ++g) {
      d.groups[g].thread = std::thread([&d, g] { d.runConsumerGroup(d.groups[g], static_cast<int>(g)); });
    }
    d.groups[0].thread = std::thread([&d] { d.runSourceGroup(d.groups[0]); });
    // The caller's thread watches for a stop request until the source is done, so a source blocked
    // inside a device read is interrupted even when its own thread cannot look.
    while (!d.source_finished.load(std::memory_order_acquire)) {
      if (d.options.stop_requested && d.options.stop_requested()) {
        d.source.interrupt();
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (Impl::Group& group : d.groups) group.thread.join();
  }
  RunReport& r = d.report;
  r.stopped = !d.aborting() && d.options.stop_requested && d.options.stop_requested();
  r.wall_s = static_cast<double>(platform::monotonicNs() - start) * 1e-9;
  r.threads = static_cast<int>(d.groups.size());
  r.stages = d.reports;
  for (const StageReport& s : r.stages) {
    r.dropped += s.dropped;
    r.damaged += s.damaged;
  }
  for (const Impl::Group& group : d.groups)
    r.released.insert(r.released.end(), group.released.begin(), group.released.end());
  std::sort(r.released.begin(), r.released.end(),
            [](const ReleasedFrame& a, const ReleasedFrame& b) { return a.time_ns < b.time_ns; });
  r.error = d.error;
  r.warnings = d.warnings;
  if (d.trace) {
    for (const ReleasedFrame& f : r.released) d.trace->released(f, d.names[static_cast<std::size_t>(f.stage)]);
    d.trace->close(r);
  }
  return std::move(d.report);
}

}  // namespace voca::pipeline
