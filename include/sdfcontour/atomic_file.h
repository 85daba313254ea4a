// Writing output files atomically: a temporary file beside the target, renamed on success.
#pragma once

#include <fstream>
#include <string>

namespace sdfcontour {

/// Opens `<path>.tmp-XXXX` for binary writing; commit() flushes and renames it over `path`.
/// If commit() is never called (an exception, say), the destructor removes the temporary file,
/// so a half-written output never appears under the final name.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& stream() { return stream_; }
  /// Flushes, checks for write errors and renames onto the final path. Throws Error on failure.
  void commit();

 private:
  std::string path_;
  std::string temporary_path_;
  std::ofstream stream_;
  bool committed_ = false;
};

}  // namespace sdfcontour
