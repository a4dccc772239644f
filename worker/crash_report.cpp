#include "worker/crash_report.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <vector>

namespace portico::crash_report {

namespace {
constexpr int kFatalSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
std::atomic<int> crashed{0};
int wake = -1;
thread_local bool tracingThread = false;

void onFatalSignal(int signal) {
  if (!tracingThread || crashed.exchange(signal) != 0) {
    // Not the tracing thread's (or a second crash): die as without a handler.
    ::signal(signal, SIG_DFL);
    ::raise(signal);
    return;
  }
  const uint64_t one = 1;
  (void)!::write(wake, &one, sizeof one);   // async-signal-safe
  for (;;) ::pause();                       // the main thread ends the process
}
}  // namespace

void install(int wakeFd) {
  wake = wakeFd;
  struct sigaction action {};
  action.sa_handler = onFatalSignal;
  action.sa_flags = SA_ONSTACK;
  sigemptyset(&action.sa_mask);
  for (int signal : kFatalSignals) ::sigaction(signal, &action, nullptr);
}

void enterTracingThread() {
  if (tracingThread) return;
  tracingThread = true;
  static thread_local std::vector<char> alternateStack(size_t(SIGSTKSZ) * 4);
  stack_t stack{};
  stack.ss_sp = alternateStack.data();
  stack.ss_size = alternateStack.size();
  ::sigaltstack(&stack, nullptr);
}

int pendingSignal() { return crashed.load(); }

void dieOf(int signal) {
  ::signal(signal, SIG_DFL);
  ::raise(signal);
  std::_Exit(128 + signal);
}

}  // namespace portico::crash_report
