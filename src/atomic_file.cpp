#include "sdfcontour/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <random>

#include "sdfcontour/types.h"

namespace sdfcontour {

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
  // The pid and a random suffix keep concurrent writers of the same target apart.
  std::random_device rd;
  temporary_path_ =
      path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(rd() % 100000);
  stream_.open(temporary_path_, std::ios::binary | std::ios::trunc);
  if (!stream_) throw Error("cannot write '" + path + "': " + std::strerror(errno));
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    stream_.close();
    std::remove(temporary_path_.c_str());
  }
}

void AtomicFile::commit() {
  stream_.flush();
  if (!stream_) throw Error("write to '" + path_ + "' failed");
  stream_.close();
  if (std::rename(temporary_path_.c_str(), path_.c_str()) != 0)
    throw Error("cannot rename the output onto '" + path_ + "': " + std::strerror(errno));
  committed_ = true;
}

}  // namespace sdfcontour
