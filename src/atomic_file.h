// Writing output files atomically: a temporary file beside the target, renamed on success.
#pragma once

#include <fstream>
#include <string>

namespace sdfcontour {

/// Opens `<path>.tmp-XXXX` for binary writing; commit() flushes and renames it over `path`.
/// If commit() is never called (an exception, say), the destructor removes the temporary file,
/// so a half-written output never appears under the final name. While an OutputBatch is open,
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

/// On SIGINT and SIGTERM, removes every temporary output file, then dies of the signal.
void remove_temporary_files_on_signals();

}  // namespace sdfcontour
