// Linked into every gtest binary: a crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL,
// SIGABRT) prints the stack to stderr before the process dies, so a crash on a
// CI machine (where run_tests keeps only the log) says where it happened.
// Addresses in our binaries resolve with `addr2line -e <binary> <offset>`.
// stdout is line-buffered too: a test's own printed lines reach the log before
// a crash (into a pipe they would otherwise wait in the buffer and be lost).
#include <execinfo.h>
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <initializer_list>

namespace {

void print_stack_and_die(int signal_number) {
  const char* name = strsignal(signal_number);
  const char header[] = "\n*** crashed: ";
  // Only async-signal-safe calls from here on (write, backtrace_symbols_fd).
  (void)!write(STDERR_FILENO, header, sizeof(header) - 1);
  (void)!write(STDERR_FILENO, name, std::strlen(name));
  (void)!write(STDERR_FILENO, "; stack:\n", 9);
  void* frames[64];
  const int depth = backtrace(frames, 64);
  backtrace_symbols_fd(frames, depth, STDERR_FILENO);
  signal(signal_number, SIG_DFL);  // die of the same signal (the exit status says so)
  raise(signal_number);
}

const bool installed = [] {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  void* warm_up[1];
  backtrace(warm_up, 1);  // loads libgcc_s now, not inside the handler
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) signal(s, print_stack_and_die);
  return true;
}();

}  // namespace
