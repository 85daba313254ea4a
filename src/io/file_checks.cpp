#include "io/file_checks.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>

#include "sdfcontour/types.h"

namespace sdfcontour {

void require_readable_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw IoError("cannot read '" + path + "': " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw IoError("cannot read '" + path + "': it is a directory");
  if (!S_ISREG(st.st_mode))
    throw IoError("cannot read '" + path + "': not a regular file (a FIFO, device or socket)");
}

namespace {

// What names a file: its device and inode if it exists, else its absolute, normalised path.
struct FileIdentity {
  bool exists = false;
  bool character_device = false;
  dev_t device = 0;
  ino_t inode = 0;
  std::string path;
  bool operator==(const FileIdentity& o) const {
    if (exists != o.exists) return false;
    return exists ? device == o.device && inode == o.inode : path == o.path;
  }
};

FileIdentity identity(const std::string& path) {
  FileIdentity id;
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    id.exists = true;
    id.character_device = S_ISCHR(st.st_mode);
    id.device = st.st_dev;
    id.inode = st.st_ino;
    return id;
  }
  std::error_code ec;
  id.path = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec).string();
  if (ec) id.path = path;
  return id;
}

}  // namespace

void require_distinct_files(const std::vector<std::string>& inputs,
                            const std::vector<std::string>& outputs) {
  std::vector<std::pair<std::string, FileIdentity>> seen;
  for (const std::string& in : inputs)
    if (!in.empty()) seen.emplace_back(in, identity(in));
  const std::size_t input_count = seen.size();
  for (const std::string& out : outputs) {
    if (out.empty()) continue;
    const FileIdentity id = identity(out);
    for (std::size_t i = 0; i < seen.size(); ++i) {
      if (!(seen[i].second == id)) continue;
      if (i < input_count)
        throw IoError("'" + out + "' is the input '" + seen[i].first +
                      "': writing it would destroy the input; choose another output name");
      if (!id.character_device)
        throw IoError("'" + out + "' and '" + seen[i].first +
                      "' are the same file: one output would overwrite the other");
    }
    seen.emplace_back(out, id);
  }
}

}  // namespace sdfcontour
