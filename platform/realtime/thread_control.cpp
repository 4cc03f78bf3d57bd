#include "platform/realtime/thread_control.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>

namespace voca::platform {

namespace {

ControlResult failure(std::string message) { return {false, std::move(message)}; }

std::string errnoText(int error) { return std::strerror(error); }

}  // namespace

int availableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return 1;
  const int count = CPU_COUNT(&set);
  return count > 0 ? count : 1;
}

ControlResult pinCurrentThread(int core) {
  if (core < 0 || core >= CPU_SETSIZE) return failure("core " + std::to_string(core) + " does not exist");
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof(allowed), &allowed) == 0 && !CPU_ISSET(core, &allowed)) {
    return failure("core " + std::to_string(core) + " is not available to this process (" +
                   std::to_string(CPU_COUNT(&allowed)) + " cores are; see taskset or the cgroup's cpuset)");
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(core, &set);
  const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
  if (rc != 0) return failure("cannot pin to core " + std::to_string(core) + ": " + errnoText(rc));
  return {};
}

std::string_view schedulingPolicyName(SchedulingPolicy policy) {
  switch (policy) {
    case SchedulingPolicy::kFifo:
      return "fifo";
    case SchedulingPolicy::kRoundRobin:
      return "rr";
    default:
      return "other";
  }
}

std::optional<SchedulingPolicy> parseSchedulingPolicy(std::string_view text) {
  if (text == "other") return SchedulingPolicy::kOther;
  if (text == "fifo") return SchedulingPolicy::kFifo;
  if (text == "rr") return SchedulingPolicy::kRoundRobin;
  return std::nullopt;
}

ControlResult setCurrentThreadScheduling(SchedulingPolicy policy, int priority) {
  int native = SCHED_OTHER;
  if (policy == SchedulingPolicy::kFifo) native = SCHED_FIFO;
  if (policy == SchedulingPolicy::kRoundRobin) native = SCHED_RR;
  const int lo = sched_get_priority_min(native), hi = sched_get_priority_max(native);
  if (priority < lo || priority > hi) {
    return failure("priority " + std::to_string(priority) + " is outside " + std::to_string(lo) + ".." +
                   std::to_string(hi) + " for " + std::string(schedulingPolicyName(policy)));
  }
  sched_param param{};
  param.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), native, &param);
  if (rc == EPERM) {
    return failure("the OS refused " + std::string(schedulingPolicyName(policy)) + " scheduling (" + errnoText(rc) +
                   "): run as root, give the binary CAP_SYS_NICE (setcap cap_sys_nice+ep), or raise RLIMIT_RTPRIO "
                   "(ulimit -r)");
  }
  if (rc != 0)
    return failure("cannot set " + std::string(schedulingPolicyName(policy)) + " scheduling: " + errnoText(rc));
  return {};
}

ControlResult lockAllMemory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return {};
  const int error = errno;
  rlimit limit{};
  getrlimit(RLIMIT_MEMLOCK, &limit);
  std::string hint = error == ENOMEM || error == EPERM
                         ? " (RLIMIT_MEMLOCK is " +
                               (limit.rlim_cur == RLIM_INFINITY ? std::string("unlimited")
                                                                : std::to_string(limit.rlim_cur / 1024) + " KiB") +
                               "; raise it with ulimit -l or run with CAP_IPC_LOCK)"
                         : "";
  return failure("cannot lock memory: " + errnoText(error) + hint);
}

void nameCurrentThread(std::string_view name) {
  char buffer[16] = {};
  const std::size_t n = name.size() < 15 ? name.size() : 15;
  std::memcpy(buffer, name.data(), n);
  pthread_setname_np(pthread_self(), buffer);
}

}  // namespace voca::platform
