#pragma once
// SIGINT/SIGTERM/SIGHUP as a flag: the handler only records the signal (async-signal-safe); shutdown
// happens in ordinary code that polls stopRequested(). A second signal exits at once.

namespace voca::platform {

// Installs the handlers for SIGINT, SIGTERM and SIGHUP (idempotent). The first signal sets the flag; the
// second ends the process immediately with 128 + signal number, for a user whose clean shutdown
// takes too long.
void installStopHandlers();

// True once a stop was requested (by a signal or requestStop()).
bool stopRequested();
// The signal that asked to stop (SIGINT = 2, SIGTERM = 15), or 0 when none did.
int stopSignal();

// Asks to stop as a signal would (tests, and code that wants the same shutdown path).
void requestStop(int signal_number = 0);
// Forgets an earlier request (tests that run several pipelines in one process).
void clearStopRequest();

// The exit code for a run that stopped because of a signal: 128 + signal number (130 for SIGINT,
// 143 for SIGTERM), as shells report a process killed by it.
int interruptedExitCode(int signal_number);

}  // namespace voca::platform
