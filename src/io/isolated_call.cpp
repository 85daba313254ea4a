#include "io/isolated_call.h"

#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <new>

#include "sdfcontour/types.h"

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFCONTOUR_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define SDFCONTOUR_ASAN 1
#endif

// Set by a sanitizer runtime (and libFuzzer) to report a crash as the process's own; absent in a
// normal build.
extern "C" void __sanitizer_set_death_callback(void (*callback)()) __attribute__((weak));

namespace sdfcontour::detail {

namespace {

// The child's reply: one status byte, then the payload (the result, or an error message).
enum Status : char { kResult = 0, kInputError = 1, kIoError = 2, kOutOfMemory = 3, kOther = 4 };

bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n, size -= std::size_t(n);
  }
  return true;
}

// The wall-clock backstop over the CPU-time limit: the reader's CPU time is what a hostile file
// drives up; on a loaded machine (a parallel test suite beside a benchmark) 5 s of CPU took longer
// than 5 s of wall time.
constexpr double kWallFactor = 4, kWallSlack = 10;
// Processor seconds under which a child that timed out counts as stalled, not busy.
constexpr double kStalledSeconds = 0.5;

[[noreturn]] void child(int fd, const std::function<std::string()>& work,
                        const IsolationLimits& limits) {
  // A crash in here is the reader's failure, reported by the parent: die by the signal, without
  // the parent's crash handlers (a fuzzer's would file it as its own finding).
  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGXCPU}) ::signal(sig, SIG_DFL);
  if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(nullptr);
#ifdef SDFCONTOUR_ASAN  // ASan reserves its shadow memory up front: a data limit breaks it
  (void)limits.memory_bytes;
#else
  if (limits.memory_bytes > 0) {
    const rlimit limit{rlim_t(limits.memory_bytes), rlim_t(limits.memory_bytes)};
    ::setrlimit(RLIMIT_DATA, &limit);
  }
#endif
  // The reader's own time: a hostile file that spins ends here; a loaded machine only stretches
  // the wall-clock backstop below (kWallFactor).
  const rlim_t cpu = rlim_t(std::ceil(limits.seconds));
  const rlimit cpu_limit{cpu, cpu + 1};
  ::setrlimit(RLIMIT_CPU, &cpu_limit);
  std::string reply(1, kOther);
  try {
    reply += work();
    reply[0] = kResult;
  } catch (const IoError& e) {
    reply = std::string(1, kIoError) + e.what();
  } catch (const Error& e) {
    reply = std::string(1, kInputError) + e.what();
  } catch (const std::bad_alloc&) {
    reply = std::string(1, kOutOfMemory);
  } catch (const std::exception& e) {
    reply = std::string(1, kOther) + e.what();
  } catch (...) {
  }
  const bool ok = write_all(fd, reply.data(), reply.size());
  ::_exit(ok ? 0 : 1);  // no atexit handlers, no destructors of the parent's state
}

}  // namespace

namespace {

// One child's run: what it wrote, how it ended, and the processor time it used.
struct ChildRun {
  std::string reply;
  int status = 0;
  bool timed_out = false;
  double cpu_seconds = 0;
};

ChildRun run_child(const std::function<std::string()>& work, const std::string& what,
                   const IsolationLimits& limits, double wall) {
  ChildRun run;
  int fds[2];
  if (::pipe(fds) != 0) throw IoError(what + ": cannot create a pipe: " + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]), ::close(fds[1]);
    throw IoError(what + ": cannot start the reader: " + std::strerror(errno));
  }
  if (pid == 0) {
    ::close(fds[0]);
    child(fds[1], work, limits);
  }
  ::close(fds[1]);
  std::string& reply = run.reply;
  bool& timed_out = run.timed_out;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wall);
  char buffer[1 << 16];
  for (;;) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, int(std::min(left * 1000 + 1, 1e9)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buffer, std::size_t(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  rusage usage{};
  while (::wait4(pid, &run.status, 0, &usage) < 0 && errno == EINTR) {
  }
  auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  run.cpu_seconds = seconds(usage.ru_utime) + seconds(usage.ru_stime);
  return run;
}

}  // namespace

std::string run_isolated(const std::function<std::string()>& work, const std::string& what,
                         const IsolationLimits& limits) {
  const double wall = kWallFactor * limits.seconds + kWallSlack;
  ChildRun run = run_child(work, what, limits, wall);
  // A child that used almost no processor time in all that wall time never ran: it waits on a
  // lock that another thread held when it was forked (the box-by-box reads fork from the bricks'
  // worker threads). Once more; a hostile file spends its time and is not retried.
  if (run.timed_out && run.cpu_seconds < kStalledSeconds) run = run_child(work, what, limits, wall);
  const int status = run.status;
  const bool timed_out = run.timed_out;
  std::string& reply = run.reply;
  if (timed_out)
    throw IoError(what + ": the reader took longer than " + std::to_string(int(wall)) + " s");
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGXCPU)
    throw IoError(what + ": the reader took longer than " + std::to_string(int(limits.seconds)) +
                  " s of processor time");
  if (WIFSIGNALED(status) || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || reply.empty())
    throw IoError(what + ": the file made the reader fail" +
                  (WIFSIGNALED(status) ? " (signal " + std::to_string(WTERMSIG(status)) + ")"
                                       : std::string()));
  const char status_byte = reply[0];
  std::string payload = std::move(reply.erase(0, 1));  // no copy of a large reply
  switch (status_byte) {
    case kResult:
      return payload;
    case kInputError:
      throw Error(payload);
    case kIoError:
      throw IoError(payload);
    case kOutOfMemory:
      throw IoError(what + ": reading it needs more memory than such a file should");
    default:
      throw IoError(what + (payload.empty() ? std::string() : ": " + payload));
  }
}

}  // namespace sdfcontour::detail
