#include "sdfcontour/io/npy.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "io/atomic_file.h"
#include "io/file_checks.h"

namespace sdfcontour {

namespace {

// Headers of real .npy files are a few hundred bytes; refuse absurd ones before parsing.
constexpr std::size_t kMaxHeaderBytes = 1 << 16;

// A read-only memory mapping of a whole file.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    require_readable_file(path);
    // Non-blocking: a FIFO swapped in after the check must not block the open.
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd_ < 0) throw IoError("cannot read '" + path + "': " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw IoError("cannot read '" + path + "': not a regular file");
    }
    size_ = std::size_t(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
      if (p == MAP_FAILED) {
        ::close(fd_);
        throw IoError("cannot read '" + path + "': " + std::strerror(errno));
      }
      data_ = static_cast<const char*>(p);
    }
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
    if (fd_ >= 0) ::close(fd_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  const char* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  int fd_ = -1;
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

// The header dict's parts, parsed by hand: {'descr': '<f8', 'fortran_order': False,
// 'shape': (3, 4), }. Keys in any order; unknown keys are an error.
struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::size_t> shape;
};

class HeaderParser {
 public:
  HeaderParser(const std::string& text, const std::string& path) : t_(text), path_(path) {}

  NpyHeader parse() {
    NpyHeader h;
    bool has_descr = false, has_order = false, has_shape = false;
    expect('{');
    while (true) {
      skip_space();
      if (peek() == '}') break;
      const std::string key = quoted();
      expect(':');
      if (key == "descr") {
        h.descr = quoted();
        has_descr = true;
      } else if (key == "fortran_order") {
        h.fortran_order = boolean();
        has_order = true;
      } else if (key == "shape") {
        h.shape = shape();
        has_shape = true;
      } else {
        fail("unknown header key '" + key + "'");
      }
      skip_space();
      if (peek() == ',') ++at_;
    }
    if (!has_descr) fail("header has no 'descr'");
    if (!has_order) fail("header has no 'fortran_order'");
    if (!has_shape) fail("header has no 'shape'");
    return h;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw Error("'" + path_ + "' is not a valid .npy file: " + what);
  }
  void skip_space() {
    while (at_ < t_.size() && (t_[at_] == ' ' || t_[at_] == '\t' || t_[at_] == '\n')) ++at_;
  }
  char peek() {
    skip_space();
    if (at_ >= t_.size()) fail("header ends early");
    return t_[at_];
  }
  void expect(char c) {
    if (peek() != c) fail(std::string("expected '") + c + "' in the header");
    ++at_;
  }
  std::string quoted() {
    const char q = peek();
    if (q != '\'' && q != '"') fail("expected a quoted string in the header");
    const std::size_t end = t_.find(q, at_ + 1);
    if (end == std::string::npos) fail("unterminated string in the header");
    std::string s = t_.substr(at_ + 1, end - at_ - 1);
    at_ = end + 1;
    return s;
  }
  bool boolean() {
    peek();
    for (const auto& [word, value] : {std::pair<const char*, bool>{"True", true}, {"False", false}})
      if (t_.compare(at_, std::strlen(word), word) == 0) {
        at_ += std::strlen(word);
        return value;
      }
    fail("fortran_order is neither True nor False");
  }
  std::vector<std::size_t> shape() {
    expect('(');
    std::vector<std::size_t> dims;
    while (peek() != ')') {
      if (!std::isdigit(static_cast<unsigned char>(t_[at_])))
        fail("the shape holds something other than non-negative integers");
      std::size_t v = 0;
      while (at_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[at_]))) {
        const std::size_t digit = std::size_t(t_[at_++] - '0');
        if (v > (std::numeric_limits<std::size_t>::max() - digit) / 10)
          fail("a shape dimension does not fit in 64 bits");
        v = v * 10 + digit;
      }
      dims.push_back(v);
      if (dims.size() > 32) fail("the shape has more than 32 dimensions");
      if (peek() == ',') ++at_;
    }
    ++at_;
    return dims;
  }

  const std::string& t_;
  const std::string& path_;
  std::size_t at_ = 0;
};

}  // namespace

std::shared_ptr<const MappedNpy> map_npy(const std::string& path) {
  auto file = std::make_shared<MappedFile>(path);
  const char* bytes = file->data();
  const std::size_t size = file->size();
  static const char magic[] = "\x93NUMPY";
  if (size < 10 || std::memcmp(bytes, magic, 6) != 0)
    throw Error("'" + path + "' is not a .npy file (bad magic bytes)");
  const int major = static_cast<unsigned char>(bytes[6]);
  std::size_t header_len = 0, header_start = 0;
  if (major == 1) {
    header_len = static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (size < 12) throw Error("'" + path + "' is a truncated .npy file");
    for (int b = 3; b >= 0; --b)
      header_len = (header_len << 8) | static_cast<unsigned char>(bytes[8 + b]);
    header_start = 12;
  } else {
    throw Error("'" + path + "' has unsupported .npy format version " + std::to_string(major));
  }
  if (header_len > kMaxHeaderBytes)
    throw Error("'" + path + "' is not a valid .npy file: its header claims " +
                std::to_string(header_len) + " bytes (at most " + std::to_string(kMaxHeaderBytes) +
                " are accepted)");
  if (size < header_start + header_len)
    throw Error("'" + path + "' is a truncated .npy file (header cut short)");
  const NpyHeader header =
      HeaderParser(std::string(bytes + header_start, header_len), path).parse();
  if (header.fortran_order)
    throw Error("'" + path + "' is in Fortran order; save it in C order (numpy.ascontiguousarray)");
  auto mapped = std::make_shared<MappedNpy>();
  if (header.descr == "<f8")
    mapped->type = ScalarType::Float64;
  else if (header.descr == "<f4")
    mapped->type = ScalarType::Float32;
  else
    throw Error("'" + path + "' has dtype '" + header.descr +
                "'; only little-endian float32 ('<f4') and float64 ('<f8') are supported");
  const std::size_t item = mapped->type == ScalarType::Float64 ? 8 : 4;
  std::string shape_text;
  for (std::size_t d : header.shape)
    shape_text += (shape_text.empty() ? "" : ", ") + std::to_string(d);
  shape_text = "(" + shape_text + ")";
  // Overflow-safe: the product of the dimensions times the item size must fit the file.
  const std::size_t data_start = header_start + header_len;
  const std::size_t available = size - data_start;
  std::size_t count = 1;
  bool too_large = false;
  for (std::size_t d : header.shape) {
    if (d != 0 && count > std::numeric_limits<std::size_t>::max() / item / d) too_large = true;
    count = too_large ? 0 : count * d;
  }
  if (too_large || available < count * item)
    throw Error("'" + path + "' is truncated: shape " + shape_text + " needs " +
                (too_large ? std::string("more than 2^64") : std::to_string(count * item)) +
                " bytes of data, the file has " + std::to_string(available));
  if (available > count * item)
    throw Error("'" + path + "' is corrupt: " + std::to_string(available - count * item) +
                " bytes follow the data of shape " + shape_text);
  mapped->shape = header.shape;
  mapped->count = count;
  mapped->data = bytes + data_start;
  mapped->file = file;
  return mapped;
}

NpyArray read_npy(const std::string& path) {
  const auto mapped = map_npy(path);
  NpyArray array;
  array.shape = mapped->shape;
  array.data.resize(mapped->count);
  for (std::size_t i = 0; i < mapped->count; ++i) array.data[i] = mapped->value(i);
  return array;
}

namespace {

// Writes a .npy file of `shape` and dtype `descr` atomically; `write_data` writes the values.
template <class WriteData>
void write_npy_file(const std::string& path, const std::vector<std::size_t>& shape,
                    const char* descr, WriteData&& write_data) {
  std::string shape_text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i)
    shape_text += (i ? ", " : "") + std::to_string(shape[i]);
  shape_text += shape.size() == 1 ? ",)" : ")";
  std::string header = std::string("{'descr': '") + descr +
                       "', 'fortran_order': False, 'shape': " + shape_text + ", }";
  // Pad so that the data starts at a multiple of 64 bytes, ending the header with '\n'.
  const std::size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out.write("\x93NUMPY\x01\x00", 8);
  const uint16_t len = uint16_t(header.size());
  const char len_bytes[2] = {char(len & 0xff), char(len >> 8)};
  out.write(len_bytes, 2);
  out.write(header.data(), std::streamsize(header.size()));
  write_data(out);
  file.commit();
}

}  // namespace

void write_npy(const std::string& path, const std::vector<std::size_t>& shape, const double* values,
               std::size_t count, ScalarType type) {
  std::size_t expected = 1;
  for (std::size_t d : shape) expected *= d;
  if (count != expected)
    throw InternalError("write_npy: " + std::to_string(count) + " values for shape of " +
                        std::to_string(expected));
  if (type == ScalarType::Float64) {
    write_npy_file(path, shape, "<f8", [&](std::ostream& out) {
      out.write(reinterpret_cast<const char*>(values), std::streamsize(count * sizeof(double)));
    });
    return;
  }
  // Converted a chunk at a time: a 1024^3 grid needs no 4 GB float copy.
  write_npy_file(path, shape, "<f4", [&](std::ostream& out) {
    std::vector<float> chunk;
    for (std::size_t at = 0; at < count; at += std::size_t(1) << 20) {
      const std::size_t k = std::min(count - at, std::size_t(1) << 20);
      chunk.assign(values + at, values + at + k);
      out.write(reinterpret_cast<const char*>(chunk.data()), std::streamsize(k * sizeof(float)));
    }
  });
}

void write_npy(const std::string& path, const std::vector<std::size_t>& shape,
               const std::vector<double>& data) {
  write_npy(path, shape, data.data(), data.size(), ScalarType::Float64);
}

namespace {

// Drops the pages of [address, address + bytes) clipped to the mapped values [values,
// values + size): whole pages, rounded outwards (the mapping is page-aligned and covers the
// values, so the rounded range stays inside it). MADV_DONTNEED on a private, never-written file
// mapping only drops clean pages, read from the file again when used (advice, so a failure
// changes nothing).
void drop_mapped_pages(const char* values, std::size_t size, const void* address,
                       std::size_t bytes) {
  const auto lo = std::max(reinterpret_cast<std::uintptr_t>(address),
                           reinterpret_cast<std::uintptr_t>(values)),
             hi = std::min(reinterpret_cast<std::uintptr_t>(address) + bytes,
                           reinterpret_cast<std::uintptr_t>(values) + size);
  if (lo >= hi) return;
  const auto page = std::uintptr_t(::sysconf(_SC_PAGESIZE));
  const std::uintptr_t first = lo / page * page, last = (hi + page - 1) / page * page;
  ::madvise(reinterpret_cast<void*>(first), last - first, MADV_DONTNEED);
}

// Grids up to this many bytes keep their pages mapped (no GridView::drop_pages): 512^3 float32
// and float64 keep theirs, 1024^3 (4 GB at float32) drops them.
constexpr std::size_t kKeepPagesUpTo = std::size_t(1024) << 20;

// A mapped .npy's grid and the page dropper its view points to (GridView::drop_pages).
struct MappedGrid {
  std::shared_ptr<const MappedNpy> array;
  std::function<void(const void*, std::size_t)> drop;
};

}  // namespace

void release_resident_pages(const SdfInput& input) {
  const GridInput* grid = std::get_if<GridInput>(&input);
  if (!grid || !grid->view.data || !grid->view.drop_pages) return;
  const std::size_t item = grid->view.type == ScalarType::Float32 ? 4 : 8;
  (*grid->view.drop_pages)(grid->view.data, grid->view.size() * item);
}

SdfInput grid_input(Grid grid) {
  auto owned = std::make_shared<Grid>(std::move(grid));
  return GridInput{view_of(*owned), owned};
}

namespace {

std::string shape_string(const std::vector<std::size_t>& shape) {
  std::string text;
  for (std::size_t d : shape) text += (text.empty() ? "" : ", ") + std::to_string(d);
  return "(" + text + ")";
}

template <class ValueAt>
SdfInput scattered_input(std::size_t rows, ValueAt&& value_at) {
  ScatteredInput input;
  const Eigen::Index n = Eigen::Index(rows);
  input.samples.points.resize(n, 3);
  input.samples.values.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) input.samples.points(i, a) = value_at(std::size_t(4 * i + a));
    input.samples.values[i] = value_at(std::size_t(4 * i + 3));
  }
  validate_samples(input.samples);
  return input;
}

[[noreturn]] void unknown_layout(const std::vector<std::size_t>& shape) {
  throw Error("array of shape " + shape_string(shape) +
              " is neither a grid (nx, ny, nz) nor scattered samples (n, 4)");
}

void check_grid_dims(const std::vector<std::size_t>& shape) {
  for (std::size_t d : shape)
    if (d > std::size_t(std::numeric_limits<int>::max()))
      throw Error("grid of shape " + shape_string(shape) + " is too large");
}

}  // namespace

SdfInput sdf_input_from_array(const NpyArray& array, const Bounds& bounds) {
  if (array.shape.size() == 3) {
    check_grid_dims(array.shape);
    Grid grid;
    for (int a = 0; a < 3; ++a) grid.dims[a] = int(array.shape[std::size_t(a)]);
    grid.bounds = bounds;
    grid.values =
        Eigen::Map<const Eigen::VectorXd>(array.data.data(), Eigen::Index(array.data.size()));
    validate_grid(grid);
    return grid_input(std::move(grid));
  }
  if (array.shape.size() == 2 && array.shape[1] == 4)
    return scattered_input(array.shape[0], [&](std::size_t i) { return array.data[i]; });
  unknown_layout(array.shape);
}

SdfInput sdf_input_from_npy(std::shared_ptr<const MappedNpy> array, const Bounds& bounds) {
  if (array->shape.size() == 3) {
    check_grid_dims(array->shape);
    const std::size_t item = array->type == ScalarType::Float32 ? 4 : 8;
    // A header of unusual length leaves the data unaligned: copy it then (numpy never does).
    if (reinterpret_cast<std::uintptr_t>(array->data) % item != 0) {
      NpyArray copy;
      copy.shape = array->shape;
      copy.data.resize(array->count);
      for (std::size_t i = 0; i < array->count; ++i) copy.data[i] = array->value(i);
      return sdf_input_from_array(copy, bounds);
    }
    GridInput input;
    for (int a = 0; a < 3; ++a) input.view.dims[a] = int(array->shape[std::size_t(a)]);
    input.view.bounds = bounds;
    input.view.data = array->data;
    input.view.type = array->type;
    auto mapped = std::make_shared<MappedGrid>();
    mapped->array = array;
    mapped->drop = [values = array->data, size = array->count * item](const void* address,
                                                                      std::size_t bytes) {
      drop_mapped_pages(values, size, address, bytes);
    };
    // A grid that memory holds many times over keeps its pages: dropping them behind each
    // measuring pass only makes the next pass fault them in again (bunny 256^3, float64, edge
    // fans: the measuring 0.57 -> 0.19 s, the whole run 5.2 -> 3.9 s; armadillo 512^3, float32:
    // 2.0-2.2 -> 0.8-0.9 s and 13.5-14.4 -> 10.9-12.3 s, its peak 0.39 -> 0.91 GB).
    if (array->count * item > kKeepPagesUpTo) input.view.drop_pages = &mapped->drop;
    input.storage = mapped;
    validate_grid(input.view);
    input.view.values_checked = true;  // the pipeline's own checks need not pass over them again
    return input;
  }
  if (array->shape.size() == 2 && array->shape[1] == 4)
    return scattered_input(array->shape[0], [&](std::size_t i) { return array->value(i); });
  unknown_layout(array->shape);
}

}  // namespace sdfcontour
