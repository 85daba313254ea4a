// Checks on the files a run reads and writes, made before any work: what would block, read
// without end, or overwrite an input is refused with a one-line IoError.
#pragma once

#include <string>
#include <vector>

namespace sdfcontour {

/// Throws IoError unless `path` (links followed) is a regular file that exists: a folder, a FIFO
/// (whose open would block), a device (/dev/zero reads without end) or a socket is refused.
void require_readable_file(const std::string& path);

/// Throws IoError if an output is one of the inputs, or two outputs are the same file: the same
/// device and inode where the files exist (links and other names included), else the same
/// absolute path. Character devices (/dev/null, a terminal) may repeat among the outputs. Empty
/// paths are skipped.
void require_distinct_files(const std::vector<std::string>& inputs,
                            const std::vector<std::string>& outputs);

}  // namespace sdfcontour
