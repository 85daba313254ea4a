#include "sdfcontour/npy.h"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "sdfcontour/atomic_file.h"

namespace sdfcontour {

namespace {

std::string read_whole_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error("cannot read '" + path + "': it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read '" + path + "': " + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  std::string bytes(static_cast<std::size_t>(std::max<std::streamoff>(size, 0)), '\0');
  if (size < 0 || !in.read(bytes.data(), size))
    throw Error("cannot read '" + path + "': I/O error");
  return bytes;
}

// Returns the value text of `key` in the header dict, e.g. "'<f8'" or "(3, 4)".
std::string header_field(const std::string& header, const std::string& key,
                         const std::string& path) {
  const std::regex pattern("'" + key + "'\\s*:\\s*('[^']*'|\\([^)]*\\)|True|False)");
  std::smatch m;
  if (!std::regex_search(header, m, pattern))
    throw Error("'" + path + "' is not a valid .npy file: header has no '" + key + "'");
  return m[1].str();
}

}  // namespace

NpyArray read_npy(const std::string& path) {
  const std::string bytes = read_whole_file(path);
  static const char magic[] = "\x93NUMPY";
  if (bytes.size() < 10 || bytes.compare(0, 6, magic, 6) != 0)
    throw Error("'" + path + "' is not a .npy file (bad magic bytes)");
  const int major = static_cast<unsigned char>(bytes[6]);
  std::size_t header_len = 0, header_start = 0;
  if (major == 1) {
    header_len = static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw Error("'" + path + "' is a truncated .npy file");
    header_len = 0;
    for (int b = 3; b >= 0; --b)
      header_len = (header_len << 8) | static_cast<unsigned char>(bytes[8 + b]);
    header_start = 12;
  } else {
    throw Error("'" + path + "' has unsupported .npy format version " + std::to_string(major));
  }
  if (bytes.size() < header_start + header_len)
    throw Error("'" + path + "' is a truncated .npy file (header cut short)");
  const std::string header = bytes.substr(header_start, header_len);

  const std::string descr = header_field(header, "descr", path);
  const std::string fortran = header_field(header, "fortran_order", path);
  const std::string shape_text = header_field(header, "shape", path);
  if (fortran == "True")
    throw Error("'" + path + "' is in Fortran order; save it in C order (numpy.ascontiguousarray)");
  std::size_t item = 0;
  if (descr == "'<f8'")
    item = 8;
  else if (descr == "'<f4'")
    item = 4;
  else
    throw Error("'" + path + "' has dtype " + descr +
                "; only little-endian float32 ('<f4') and float64 ('<f8') are supported");

  NpyArray array;
  std::string dims = shape_text.substr(1, shape_text.size() - 2);
  std::stringstream ss(dims);
  std::string token;
  std::size_t count = 1;
  while (std::getline(ss, token, ',')) {
    const auto first = token.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    std::size_t pos = 0;
    unsigned long long v = 0;
    try {
      v = std::stoull(token.substr(first), &pos);
    } catch (const std::exception&) {
      throw Error("'" + path + "' has a corrupt shape " + shape_text);
    }
    array.shape.push_back(std::size_t(v));
    count *= std::size_t(v);
  }
  const std::size_t data_start = header_start + header_len;
  const std::size_t available = bytes.size() - data_start;
  if (available < count * item)
    throw Error("'" + path + "' is truncated: shape " + shape_text + " needs " +
                std::to_string(count * item) + " bytes of data, the file has " +
                std::to_string(available));
  if (available > count * item)
    throw Error("'" + path + "' is corrupt: " + std::to_string(available - count * item) +
                " bytes follow the data of shape " + shape_text);
  array.data.resize(count);
  const char* p = bytes.data() + data_start;
  for (std::size_t i = 0; i < count; ++i) {
    if (item == 8) {
      double v;
      std::memcpy(&v, p + 8 * i, 8);
      array.data[i] = v;
    } else {
      float v;
      std::memcpy(&v, p + 4 * i, 4);
      array.data[i] = v;
    }
  }
  return array;
}

void write_npy(const std::string& path, const std::vector<std::size_t>& shape,
               const std::vector<double>& data) {
  std::string shape_text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i)
    shape_text += (i ? ", " : "") + std::to_string(shape[i]);
  shape_text += shape.size() == 1 ? ",)" : ")";
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': " + shape_text + ", }";
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
  out.write(reinterpret_cast<const char*>(data.data()),
            std::streamsize(data.size() * sizeof(double)));
  file.commit();
}

SdfInput sdf_input_from_array(const NpyArray& array, const Bounds& bounds) {
  SdfInput input;
  std::string shape_text;
  for (std::size_t d : array.shape)
    shape_text += (shape_text.empty() ? "" : ", ") + std::to_string(d);
  shape_text = "(" + shape_text + ")";
  if (array.shape.size() == 3) {
    input.is_grid = true;
    for (int a = 0; a < 3; ++a) input.grid.dims[a] = int(array.shape[a]);
    input.grid.bounds = bounds;
    input.grid.values =
        Eigen::Map<const Eigen::VectorXd>(array.data.data(), Eigen::Index(array.data.size()));
    validate_grid(input.grid);
    return input;
  } else if (array.shape.size() == 2 && array.shape[1] == 4) {
    const Eigen::Index n = Eigen::Index(array.shape[0]);
    input.samples.points.resize(n, 3);
    input.samples.values.resize(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) input.samples.points(i, a) = array.data[std::size_t(4 * i + a)];
      input.samples.values[i] = array.data[std::size_t(4 * i + 3)];
    }
  } else {
    throw Error("array of shape " + shape_text +
                " is neither a grid (nx, ny, nz) nor scattered samples (n, 4)");
  }
  validate_samples(input.samples);
  return input;
}

}  // namespace sdfcontour
