#pragma once
// Real-time controls for the calling thread and process: core affinity, a real-time scheduling
// class, and locking memory against paging. Each returns what happened instead of throwing, so a
// run on a machine that refuses (no CAP_SYS_NICE, RLIMIT_MEMLOCK too low) warns once and goes on.

#include <optional>
#include <string>
#include <string_view>

namespace voca::platform {

// The outcome of one request: ok, or the reason the OS gave and what to do about it.
struct ControlResult {
  bool ok = true;
  std::string message;  // empty when ok
};

// Number of cores this process may run on (sched_getaffinity), at least 1.
int availableCores();

// Pins the calling thread to one core (0-based, as `taskset -c` counts).
ControlResult pinCurrentThread(int core);

// Real-time scheduling classes (sched(7)): FIFO runs until it blocks, RR shares a priority level by
// time slices. kOther is the ordinary time-sharing class.
enum class SchedulingPolicy { kOther, kFifo, kRoundRobin };
std::string_view schedulingPolicyName(SchedulingPolicy policy);
// "other", "fifo", "rr"; nullopt for anything else.
std::optional<SchedulingPolicy> parseSchedulingPolicy(std::string_view text);

// Gives the calling thread a scheduling class and priority (1..99 for the real-time classes).
ControlResult setCurrentThreadScheduling(SchedulingPolicy policy, int priority);

// Locks the process's current and future pages in RAM (mlockall), so a page fault never stalls a stage.
ControlResult lockAllMemory();

// Names the calling thread (visible in top -H, perf and gdb); at most 15 characters are kept.
void nameCurrentThread(std::string_view name);

}  // namespace voca::platform
