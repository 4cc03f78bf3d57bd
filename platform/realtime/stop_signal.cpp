#include "platform/realtime/stop_signal.h"

#include <unistd.h>
#include <csignal>

#include <atomic>

namespace voca::platform {

namespace {

std::atomic<int> g_stop_signal{0};  // lock-free int: safe to write from a handler
std::atomic<bool> g_stop{false};
std::atomic<bool> g_installed{false};

extern "C" void onStopSignal(int signal_number) {
  if (g_stop.exchange(true)) _exit(128 + signal_number);
  g_stop_signal.store(signal_number);
}

}  // namespace

void installStopHandlers() {
  if (g_installed.exchange(true)) return;
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a blocking read returns EINTR and the stop is seen sooner
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  // The terminal or ssh session went away: stop the same clean way, so what was estimated is kept.
  sigaction(SIGHUP, &action, nullptr);
}

bool stopRequested() { return g_stop.load(std::memory_order_relaxed); }
int stopSignal() { return g_stop_signal.load(std::memory_order_relaxed); }

void requestStop(int signal_number) {
  g_stop_signal.store(signal_number);
  g_stop.store(true);
}

void clearStopRequest() {
  g_stop.store(false);
  g_stop_signal.store(0);
}

int interruptedExitCode(int signal_number) { return 128 + signal_number; }

}  // namespace voca::platform
