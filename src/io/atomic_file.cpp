#include "io/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

#include "sdfcontour/types.h"

namespace sdfcontour {

namespace {

// Temporary files alive now, in fixed storage a signal handler can read without allocating.
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
char g_paths[kSlots][kPathBytes];
std::atomic<bool> g_used[kSlots];

int register_temporary(const std::string& path) {
  if (path.size() + 1 > kPathBytes) return -1;
  for (int s = 0; s < kSlots; ++s) {
    bool expected = false;
    if (g_used[s].compare_exchange_strong(expected, true)) {
      std::memcpy(g_paths[s], path.c_str(), path.size() + 1);
      return s;
    }
  }
  return -1;  // more than kSlots outputs at once: still removed by the destructor
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_used[slot] = false;
}

int slot_of(const std::string& path) {
  for (int s = 0; s < kSlots; ++s)
    if (g_used[s] && path == g_paths[s]) return s;
  return -1;
}

// The open batch's completed files: (temporary, final).
std::mutex g_batch_mutex;
bool g_batch_open = false;
std::vector<std::pair<std::string, std::string>> g_pending;

extern "C" void remove_and_die(int signal) {
  for (int s = 0; s < kSlots; ++s)
    if (g_used[s]) ::unlink(g_paths[s]);
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

// A mapped input cut short under us (the file truncated while it is read) raises SIGBUS at the
// first page past its new end: one error line, the temporary files removed, exit 1. (Only
// async-signal-safe calls.)
extern "C" void input_cut_short(int) {
  for (int s = 0; s < kSlots; ++s)
    if (g_used[s]) ::unlink(g_paths[s]);
  static const char message[] =
      "sdfcontour: error: an input file was truncated or removed while it was read\n";
  const ssize_t written = ::write(2, message, sizeof message - 1);
  (void)written;
  ::_exit(1);
}

}  // namespace

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    // A device, FIFO or a link to one (/dev/stdout): written in place; a rename would replace
    // it with a regular file.
    in_place_ = true;
    stream_.open(path, std::ios::binary);
    if (!stream_) throw IoError("cannot write '" + path + "': " + std::strerror(errno));
    return;
  }
  std::error_code ec;
  if (std::filesystem::is_symlink(path, ec)) {
    // A link to a regular file (or to nothing yet): the file behind it is replaced, the link kept.
    const auto target = std::filesystem::weakly_canonical(path, ec);
    if (!ec) path_ = target.string();
  }
  // Beside the target (rename stays in one file system), named apart from it: a target name of
  // the file system's longest still has a temporary one. The pid and a random number keep
  // concurrent writers apart.
  std::random_device rd;
  const std::filesystem::path target(path_);
  temporary_path_ = (target.parent_path() / (".sdfcontour.tmp-" + std::to_string(::getpid()) + "-" +
                                             std::to_string(rd() % 100000)))
                        .string();
  register_temporary(temporary_path_);
  stream_.open(temporary_path_, std::ios::binary | std::ios::trunc);
  if (!stream_) {
    unregister_temporary(slot_of(temporary_path_));
    throw IoError("cannot write '" + path + "': " + std::strerror(errno));
  }
}

AtomicFile::~AtomicFile() {
  if (!committed_ && !in_place_) {
    stream_.close();
    std::remove(temporary_path_.c_str());
    unregister_temporary(slot_of(temporary_path_));
  }
}

void AtomicFile::commit() {
  stream_.flush();
  if (!stream_) throw IoError("write to '" + path_ + "' failed");
  stream_.close();
  if (in_place_) {
    committed_ = true;
    return;
  }
  {
    std::lock_guard<std::mutex> lock(g_batch_mutex);
    if (g_batch_open) {
      g_pending.emplace_back(temporary_path_, path_);
      committed_ = true;
      return;
    }
  }
  if (std::rename(temporary_path_.c_str(), path_.c_str()) != 0)
    throw IoError("cannot rename the output onto '" + path_ + "': " + std::strerror(errno));
  unregister_temporary(slot_of(temporary_path_));
  committed_ = true;
}

OutputBatch::OutputBatch() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  g_batch_open = true;
  g_pending.clear();
}

OutputBatch::~OutputBatch() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  for (const auto& [temporary, final_path] : g_pending) {
    std::remove(temporary.c_str());
    unregister_temporary(slot_of(temporary));
  }
  g_pending.clear();
  g_batch_open = false;
}

void OutputBatch::commit() {
  std::lock_guard<std::mutex> lock(g_batch_mutex);
  for (const auto& [temporary, final_path] : g_pending) {
    if (std::rename(temporary.c_str(), final_path.c_str()) != 0)
      throw IoError("cannot rename the output onto '" + final_path + "': " + std::strerror(errno));
    unregister_temporary(slot_of(temporary));
  }
  g_pending.clear();
}

void require_writable(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  if (fs::is_directory(p, ec)) throw IoError("cannot write '" + path + "': it is a directory");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {  // a device or FIFO: in place
    if (::access(path.c_str(), W_OK) != 0)
      throw IoError("cannot write '" + path + "': " + std::strerror(errno));
    return;
  }
  const fs::path folder = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(folder, ec))
    throw IoError("cannot write '" + path + "': folder '" + folder.string() + "' does not exist");
  if (::access(folder.c_str(), W_OK) != 0)
    throw IoError("cannot write '" + path + "': " + std::strerror(errno));
}

void remove_temporary_files_on_signals() {
  // Every signal whose default action terminates the process: a closed terminal (SIGHUP), a
  // closed pipe (SIGPIPE, progress piped into head), timers and limits.
  for (int signal : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGQUIT, SIGALRM, SIGUSR1, SIGUSR2, SIGXCPU,
                     SIGXFSZ, SIGVTALRM, SIGPROF})
    std::signal(signal, remove_and_die);
  std::signal(SIGBUS, input_cut_short);
}

}  // namespace sdfcontour
