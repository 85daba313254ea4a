// Writing output files atomically: a temporary file beside the target, renamed on success.
#pragma once

#include <fstream>
#include <string>

namespace sdfcontour {

/// Opens `<path>.tmp-XXXX` for binary writing; commit() flushes and renames it over `path`.
/// If commit() is never called (an exception, say), the destructor removes the temporary file,
/// so a half-written output never appears under the final name. A path that names a device or
/// FIFO (/dev/stdout, or a link to one) is written in place instead; a link to a regular file
/// keeps the link and replaces the file behind it. While an OutputBatch is open,
/// commit() only completes the file: the rename waits for the batch.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& stream() { return stream_; }
  /// Flushes, checks for write errors and renames onto the final path (or hands the file to the
  /// open OutputBatch). Throws Error on failure.
  void commit();

 private:
  std::string path_;
  std::string temporary_path_;
  std::ofstream stream_;
  bool committed_ = false;
  bool in_place_ = false;  ///< a device or FIFO, written directly
};

/// All outputs of one run, renamed together: while a batch is open, completed AtomicFiles wait
/// as temporary files; commit() renames them all, and a batch destroyed without commit() (a
/// later output failed) removes them, so a failed run leaves no output behind. One batch at a
/// time, per process.
class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  void commit();
};

/// Throws Error unless `path` could be created: its folder exists and is writable, and it is not
/// a folder itself. Checked before long work, so a bad output path fails fast.
void require_writable(const std::string& path);

/// On every terminating signal (SIGINT, SIGTERM, SIGHUP, SIGPIPE, ...), removes every temporary
/// output file, then dies of the signal. On SIGBUS (a mapped input truncated while it is read),
/// removes them, says so in one error line and exits with status 1. For the command-line tool: a
/// library inside another program leaves that program's signals alone.
void remove_temporary_files_on_signals();

}  // namespace sdfcontour
