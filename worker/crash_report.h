// A worker that crashes tracing a lease says so before it dies. A fatal
// signal (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) on the tracing thread
// is what the cell did to it; the handler parks that thread and wakes the
// main thread, whose socket is intact, to report the lease as failed (a
// Failure, which the coordinator counts against the cell) and then end the
// process with the same signal. A worker that is simply gone (SIGKILL, the
// OOM killer, a lost node) reports nothing: the coordinator tells the two
// apart by that.
#pragma once

#include <string>

namespace portico::crash_report {

// Installs the handlers; a crash on the tracing thread writes to `wakeFd`
// (an eventfd the main loop polls).
void install(int wakeFd);
// The calling thread traces leases: its fatal signals are reported (on an
// alternate stack, so a stack overflow is reported too).
void enterTracingThread();
// 0, or the signal the tracing thread crashed with.
int pendingSignal();
// Ends the process with `signal`, as the crash would have.
[[noreturn]] void dieOf(int signal);

}  // namespace portico::crash_report
