#include "io/vdb_replies.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace sdfcontour::detail {

namespace {

template <class T>
void put(std::string& out, const T* data, std::size_t count) {
  out.append(reinterpret_cast<const char*>(data), sizeof(T) * count);
}

template <class T>
void take(const std::string& bytes, std::size_t& at, T* data, std::size_t count) {
  if (count > (bytes.size() - at) / sizeof(T))
    throw InternalError("the .vdb reader's reply is cut short");
  if (count == 0) return;  // (an empty vector's data may be null, which memcpy may not take)
  std::memcpy(data, bytes.data() + at, sizeof(T) * count);
  at += sizeof(T) * count;
}

std::string take_name(const std::string& bytes, std::size_t& at) {
  std::uint64_t size = 0;
  take(bytes, at, &size, 1);
  if (size > bytes.size() - at) throw InternalError("the .vdb reader's reply is cut short");
  std::string name(size, '\0');
  take(bytes, at, name.data(), size);
  return name;
}

// Whether the rows of r are orthonormal and right-handed, to within `tolerance`.
bool is_rotation(const Eigen::Matrix3d& r, double tolerance) {
  return r.allFinite() &&
         ((r * r.transpose()) - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         r.determinant() > 0;
}

// Whether [lo, hi] keeps kVdbIndexMargin voxels from both ends of int's range.
bool within_index_range(int lo, int hi) {
  return lo >= std::numeric_limits<int>::min() + kVdbIndexMargin &&
         hi <= std::numeric_limits<int>::max() - kVdbIndexMargin;
}

}  // namespace

std::string level_set_reply(const VdbLevelSet& s) {
  const std::uint64_t name_size = s.grid_name.size(), n = std::uint64_t(s.samples.values.size());
  std::string out;
  put(out, &name_size, 1);
  put(out, s.grid_name.data(), name_size);
  put(out, &s.voxel_size, 1);
  put(out, &s.background, 1);
  put(out, &n, 1);
  put(out, s.samples.points.data(), 3 * n);
  put(out, s.samples.values.data(), n);
  return out;
}

VdbLevelSet parse_level_set_reply(const std::string& bytes) {
  std::size_t at = 0;
  VdbLevelSet s;
  s.grid_name = take_name(bytes, at);
  take(bytes, at, &s.voxel_size, 1);
  take(bytes, at, &s.background, 1);
  std::uint64_t n = 0;
  take(bytes, at, &n, 1);
  if (n > (bytes.size() - at) / 32 || (bytes.size() - at) != 32 * n)
    throw InternalError("the .vdb reader's reply has the wrong size");
  s.samples.points.resize(Eigen::Index(n), 3);
  s.samples.values.resize(Eigen::Index(n));
  take(bytes, at, s.samples.points.data(), 3 * n);
  take(bytes, at, s.samples.values.data(), n);
  return s;
}

std::string layout_reply(const OpenVdbLayout& l) {
  const std::uint64_t name_size = l.grid_name.size(), leaves = l.leaf_origins.size();
  std::string out;
  put(out, &name_size, 1);
  put(out, l.grid_name.data(), name_size);
  put(out, l.min, 3);
  put(out, l.max, 3);
  put(out, &l.voxel, 1);
  put(out, l.origin, 3);
  put(out, l.rotation, 9);
  put(out, &l.background, 1);
  put(out, &leaves, 1);
  put(out, l.leaf_origins.data(), leaves);
  return out;
}

VdbLayout parse_layout_reply(const std::string& bytes, const std::string& path) {
  VdbLayout l;
  std::size_t at = 0;
  l.grid_name = take_name(bytes, at);
  take(bytes, at, l.min.data(), 3);
  take(bytes, at, l.max.data(), 3);
  take(bytes, at, &l.voxel_size, 1);
  take(bytes, at, l.origin.data(), 3);
  double rotation[9];
  take(bytes, at, rotation, 9);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) l.rotation(a, b) = rotation[3 * a + b];
  take(bytes, at, &l.background, 1);
  std::uint64_t leaves = 0;
  take(bytes, at, &leaves, 1);
  if (leaves % 3 != 0 || leaves > bytes.size() || bytes.size() - at != leaves * sizeof(int))
    throw InternalError("the .vdb reader's reply is malformed");
  std::vector<int> origins(leaves);
  take(bytes, at, origins.data(), leaves);
  const std::string grid = "grid '" + l.grid_name + "' in '" + path + "'";
  for (std::size_t a = 0; a < 3; ++a) {
    if (l.min[a] > l.max[a]) throw Error(grid + " has no active voxels");
    if (!within_index_range(l.min[a], l.max[a]))
      throw Error(grid + " has active voxels at the ends of OpenVDB's index range");
  }
  if (!(l.voxel_size > 0) || !std::isfinite(l.voxel_size) || !l.origin.allFinite() ||
      !is_rotation(l.rotation, 1e-6))
    throw Error(grid + " has a degenerate transform");
  if (!(l.background > 0) || !std::isfinite(l.background))
    throw Error(grid + " has a background that is not a positive number");
  // A leaf (8^3 voxels from its origin) that holds an active voxel meets the bounding box.
  for (std::size_t i = 0; i < leaves; i += 3) {
    std::array<int, 3> o{origins[i], origins[i + 1], origins[i + 2]};
    for (std::size_t a = 0; a < 3; ++a)
      if (o[a] > l.max[a] || o[a] < l.min[a] - 7)
        throw InternalError("the .vdb reader's reply has a leaf outside the active voxels");
    l.leaf_origins.push_back(o);
  }
  return l;
}

BlockedGrid blocked_grid_of(const VdbLayout& layout, const std::string& path) {
  if (layout.leaf_origins.empty())
    throw Error("grid '" + layout.grid_name + "' in '" + path + "' has no active voxels");
  BlockedGrid grid;
  std::array<int, 3> first;
  // A rotated grid is contoured in its own frame, origin at voxel (0, 0, 0).
  const Eigen::Vector3d origin =
      vdb_world_from_grid(layout) ? Eigen::Vector3d::Zero() : layout.origin;
  // (parse_layout_reply kept the box and the leaves inside the index range: no sum below
  // overflows.)
  for (std::size_t a = 0; a < 3; ++a) {
    first[a] = layout.min[a] - 1;
    const long long n = (long long)layout.max[a] - first[a] + 2;
    if (n > (1 << 30)) throw Error("the level set in '" + path + "' is too large a grid");
    grid.dims[a] = int(n);
    grid.bounds.min[a] = origin[a] + layout.voxel_size * first[a];
    grid.bounds.max[a] = origin[a] + layout.voxel_size * (first[a] + grid.dims[a] - 1);
  }
  const std::string name = layout.grid_name;
  grid.read = [path, name, first](const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    std::array<int, 3> at, dims;
    for (std::size_t a = 0; a < 3; ++a) at[a] = first[a] + lo[a], dims[a] = hi[a] - lo[a];
    return read_vdb_box(path, name, at, dims);
  };
  // The leaves (8^3 voxels) in grid indices: outside them every voxel is inactive, its value the
  // signed background (the band's half width), so no sign changes there.
  std::vector<SampleBox> leaves;
  for (const auto& o : layout.leaf_origins) {
    SampleBox box;
    for (std::size_t a = 0; a < 3; ++a) {
      box.lo[a] = o[a] - first[a];
      box.hi[a] = box.lo[a] + 8;
    }
    leaves.push_back(box);
  }
  grid.surface_boxes = std::move(leaves);
  return grid;
}

}  // namespace sdfcontour::detail
