// Linked into every gtest binary: a crash (SIGSEGV, SIGBUS, SIGFPE, SIGILL,
// SIGABRT) prints the faulting address and the stack to stderr before the
// process dies, so a crash on a CI machine (where run_tests keeps only the log)
// says where it happened. Addresses in our binaries resolve with
// `addr2line -e <binary> <offset>`. stdout is line-buffered too: a test's own
// printed lines reach the log before a crash (into a pipe they would otherwise
// wait in the buffer and be lost).
#include <execinfo.h>
#include <signal.h>
#include <ucontext.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <initializer_list>

namespace {

void say(const char* text) { (void)!write(STDERR_FILENO, text, std::strlen(text)); }

void say_hex(std::uintptr_t value) {
  char digits[2 + 2 * sizeof(value) + 1];
  digits[0] = '0';
  digits[1] = 'x';
  for (std::size_t i = 0; i < 2 * sizeof(value); ++i) {
    digits[2 + i] = "0123456789abcdef"[(value >> (4 * (2 * sizeof(value) - 1 - i))) & 0xf];
  }
  digits[sizeof(digits) - 1] = '\0';
  say(digits);
}

void print_stack_and_die(int signal_number, siginfo_t* info, void* context) {
  // The handler is reset on entry (SA_RESETHAND): if unwinding a wild stack
  // faults again, the process dies of that signal instead of looping. Only
  // async-signal-safe calls from here on (write, backtrace_symbols_fd).
  say("\n*** crashed: ");
  say(strsignal(signal_number));
  say(" at address ");
  say_hex(reinterpret_cast<std::uintptr_t>(info->si_addr));
#if defined(__x86_64__)
  // A call through a wild pointer leaves nothing to unwind (backtrace then faults
  // too): the instruction pointer, and the return address on top of the stack,
  // still say who made the call.
  const mcontext_t& registers = static_cast<ucontext_t*>(context)->uc_mcontext;
  say(", instruction ");
  say_hex(static_cast<std::uintptr_t>(registers.gregs[REG_RIP]));
  void* caller[1] = {*reinterpret_cast<void* const*>(registers.gregs[REG_RSP])};
  say(", top of the stack (after a wild call, the return address):\n");
  backtrace_symbols_fd(caller, 1, STDERR_FILENO);
#else
  (void)context;
#endif
  say("stack:\n");
  void* frames[64];
  const int depth = backtrace(frames, 64);
  backtrace_symbols_fd(frames, depth, STDERR_FILENO);
  raise(signal_number);  // the default action now: die of it (the exit status says so)
}

const bool installed = [] {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  void* warm_up[1];
  backtrace(warm_up, 1);  // loads libgcc_s now, not inside the handler
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_sigaction = print_stack_and_die;
  action.sa_flags = SA_SIGINFO | SA_RESETHAND;
  sigemptyset(&action.sa_mask);
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) sigaction(s, &action, nullptr);
  return true;
}();

}  // namespace
