#include "sdfcontour/metrics/mesh_properties.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace sdfcontour {

MeshTopology mesh_topology(const Mesh& mesh) {
  // Directed edges as (min, max, direction) sorted, then counted per undirected edge.
  std::vector<std::uint64_t> directed;
  directed.reserve(std::size_t(mesh.triangles.rows()) * 3);
  std::vector<char> used(std::size_t(mesh.vertices.rows()), 0);
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = std::uint64_t(mesh.triangles(f, k)),
                          b = std::uint64_t(mesh.triangles(f, (k + 1) % 3));
      used[a] = 1;
      directed.push_back((std::min(a, b) << 33) | (std::max(a, b) << 1) | (a < b ? 0 : 1));
    }
  std::sort(directed.begin(), directed.end());
  MeshTopology t;
  long edges = 0;
  bool oriented = true;
  for (std::size_t s = 0; s < directed.size();) {
    std::size_t e = s;
    int forward = 0, backward = 0;
    while (e < directed.size() && (directed[e] >> 1) == (directed[s] >> 1))
      (directed[e++] & 1 ? backward : forward)++;
    ++edges;
    const int count = forward + backward;
    if (count == 1) ++t.boundary_edges;
    if (count > 2) ++t.nonmanifold_edges;
    if (forward > 1 || backward > 1) oriented = false;
    s = e;
  }
  t.closed = t.boundary_edges == 0 && t.nonmanifold_edges == 0;
  t.consistently_oriented = oriented;
  const long vertices = long(std::count(used.begin(), used.end(), 1));
  t.euler_characteristic = vertices - edges + long(mesh.triangles.rows());
  return t;
}

std::vector<int> component_labels(const Mesh& mesh) {
  std::vector<int> parent(std::size_t(mesh.vertices.rows()));
  std::vector<char> used(parent.size(), 0);
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = int(i);
  auto find = [&](int x) {
    while (parent[std::size_t(x)] != x)
      x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
  };
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      used[std::size_t(mesh.triangles(f, k))] = 1;
      const int a = find(mesh.triangles(f, k)), b = find(mesh.triangles(f, (k + 1) % 3));
      if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
    }
  // Roots are the smallest vertex of their piece: numbering roots in order numbers the pieces
  // by their first vertex.
  std::vector<int> label(parent.size(), -1);
  int pieces = 0;
  for (std::size_t i = 0; i < parent.size(); ++i)
    if (used[i] && find(int(i)) == int(i)) label[i] = pieces++;
  for (std::size_t i = 0; i < parent.size(); ++i)
    if (used[i]) label[i] = label[std::size_t(find(int(i)))];
  return label;
}

namespace {

int piece_count(const std::vector<int>& labels) {
  int pieces = 0;
  for (int l : labels) pieces = std::max(pieces, l + 1);
  return pieces;
}

}  // namespace

int connected_components(const Mesh& mesh) {
  return piece_count(component_labels(mesh));
}

std::vector<Eigen::AlignedBox3d> component_boxes(const Mesh& mesh, const std::vector<int>& labels) {
  std::vector<Eigen::AlignedBox3d> boxes(std::size_t(piece_count(labels)));
  for (std::size_t v = 0; v < labels.size(); ++v)
    if (labels[v] >= 0)
      boxes[std::size_t(labels[v])].extend(mesh.vertices.row(Eigen::Index(v)).transpose());
  return boxes;
}

int remove_small_pieces(Mesh& mesh, double min_extent) {
  const std::vector<int> label = component_labels(mesh);
  const std::vector<Eigen::AlignedBox3d> boxes = component_boxes(mesh, label);
  const int pieces = int(boxes.size());
  if (pieces <= 1) return 0;
  auto small = std::vector<char>(std::size_t(pieces));
  int removed = 0;
  for (std::size_t c = 0; c < small.size(); ++c)
    removed += small[c] = boxes[c].sizes().maxCoeff() < min_extent;
  if (removed == 0 || removed == pieces) return 0;
  // Keep the other pieces' vertices and triangles, in their order.
  std::vector<int> new_index(label.size(), -1);
  int kept = 0;
  for (std::size_t v = 0; v < label.size(); ++v)
    if (label[v] >= 0 && !small[std::size_t(label[v])]) new_index[v] = kept++;
  Mesh out;
  out.vertices.resize(kept, 3);
  for (std::size_t v = 0; v < label.size(); ++v)
    if (new_index[v] >= 0) out.vertices.row(new_index[v]) = mesh.vertices.row(Eigen::Index(v));
  Eigen::Index triangles = 0;
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
    triangles += new_index[std::size_t(mesh.triangles(f, 0))] >= 0;
  out.triangles.resize(triangles, 3);
  for (Eigen::Index f = 0, t = 0; f < mesh.triangles.rows(); ++f)
    if (new_index[std::size_t(mesh.triangles(f, 0))] >= 0) {
      for (int k = 0; k < 3; ++k)
        out.triangles(t, k) = new_index[std::size_t(mesh.triangles(f, k))];
      ++t;
    }
  mesh = std::move(out);
  return removed;
}

static Eigen::Vector3d vertex(const Mesh& m, Eigen::Index f, int k) {
  return m.vertices.row(m.triangles(f, k)).transpose();
}

double surface_area(const Mesh& mesh) {
  double area = 0;
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
    area += 0.5 * (vertex(mesh, f, 1) - vertex(mesh, f, 0))
                      .cross(vertex(mesh, f, 2) - vertex(mesh, f, 0))
                      .norm();
  return area;
}

double signed_volume(const Mesh& mesh) {
  double volume = 0;
  for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
    volume += vertex(mesh, f, 0).dot(vertex(mesh, f, 1).cross(vertex(mesh, f, 2))) / 6.0;
  return volume;
}

}  // namespace sdfcontour
