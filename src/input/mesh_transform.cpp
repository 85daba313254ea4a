#include "sdfcontour/input/mesh_transform.h"

#include <map>
#include <utility>
#include <vector>

namespace sdfcontour {

Mesh normalize_mesh(const Mesh& mesh, double half_extent) {
  if (mesh.vertices.rows() == 0) throw Error("the mesh has no vertices");
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff(),
                           hi = mesh.vertices.colwise().maxCoeff();
  const double longest = (hi - lo).maxCoeff();
  if (!(longest > 0)) throw Error("the mesh has no extent");
  Mesh out = mesh;
  const Eigen::RowVector3d centre = 0.5 * (lo + hi);
  out.vertices = ((mesh.vertices.rowwise() - centre) * (2 * half_extent / longest)).eval();
  return out;
}

namespace {

// The part of a mesh on the side where coordinate `axis` times `sign` is at most `sign` * `bound`.
struct HalfSpaceClip {
  int axis;
  double sign, bound;

  double outside(const Eigen::RowVector3d& p) const { return sign * (p[axis] - bound); }

  // Replaces `triangles` by their parts inside, appending the new vertices on the plane to
  // `vertices`; true if anything was dropped or cut.
  bool apply(std::vector<Eigen::RowVector3d>& vertices,
             std::vector<Eigen::Vector3i>& triangles) const {
    std::map<std::pair<int, int>, int> cut;  // edge (low, high) -> its vertex on the plane
    auto crossing = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto found = cut.find(key);
      if (found != cut.end()) return found->second;
      // From the lower index, so both triangles of an edge get the same point.
      const Eigen::RowVector3d p = vertices[std::size_t(key.first)],
                               q = vertices[std::size_t(key.second)];
      const double dp = outside(p), dq = outside(q);
      if (dp == 0) return key.first;  // the edge leaves from a vertex on the plane
      if (dq == 0) return key.second;
      Eigen::RowVector3d x = p + (q - p) * (dp / (dp - dq));
      x[axis] = bound;
      vertices.push_back(x);
      const int id = int(vertices.size()) - 1;
      cut.emplace(key, id);
      return id;
    };
    bool changed = false;
    std::vector<Eigen::Vector3i> kept;
    kept.reserve(triangles.size());
    for (const Eigen::Vector3i& tri : triangles) {
      bool out[3];
      int outside_count = 0;
      for (int c = 0; c < 3; ++c)
        outside_count += out[c] = outside(vertices[std::size_t(tri[c])]) > 0;
      if (outside_count == 0) {
        kept.push_back(tri);
        continue;
      }
      changed = true;
      if (outside_count == 3) continue;
      // The kept polygon, corners in the triangle's order.
      std::vector<int> polygon;
      for (int c = 0; c < 3; ++c) {
        const int a = tri[c], b = tri[(c + 1) % 3];
        if (!out[c]) polygon.push_back(a);
        if (out[c] != out[(c + 1) % 3]) polygon.push_back(crossing(a, b));
      }
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        const int a = polygon[0], b = polygon[k], c = polygon[k + 1];
        if (a != b && b != c && c != a) kept.emplace_back(a, b, c);
      }
    }
    triangles = std::move(kept);
    return changed;
  }
};

}  // namespace

bool clip_mesh_to_box(Mesh& mesh, const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  // A box holding every vertex holds every triangle (the common case: nothing to copy).
  if (mesh.vertices.rows() == 0 ||
      ((mesh.vertices.colwise().minCoeff().transpose().array() >= min.array()).all() &&
       (mesh.vertices.colwise().maxCoeff().transpose().array() <= max.array()).all()))
    return false;
  std::vector<Eigen::RowVector3d> vertices(std::size_t(mesh.vertices.rows()));
  for (std::size_t v = 0; v < vertices.size(); ++v)
    vertices[v] = mesh.vertices.row(Eigen::Index(v));
  std::vector<Eigen::Vector3i> triangles(std::size_t(mesh.triangles.rows()));
  for (std::size_t t = 0; t < triangles.size(); ++t)
    triangles[t] = mesh.triangles.row(Eigen::Index(t)).transpose();
  bool changed = false;
  for (int axis = 0; axis < 3; ++axis)
    for (const HalfSpaceClip& clip :
         {HalfSpaceClip{axis, 1.0, max[axis]}, HalfSpaceClip{axis, -1.0, min[axis]}})
      changed |= clip.apply(vertices, triangles);
  if (!changed) return false;
  // Keep only the vertices the kept triangles use, in their first order.
  std::vector<int> renumber(vertices.size(), -1);
  int used = 0;
  for (const auto& t : triangles)
    for (int c = 0; c < 3; ++c)
      if (renumber[std::size_t(t[c])] < 0) renumber[std::size_t(t[c])] = used++;
  mesh.vertices.resize(used, 3);
  for (std::size_t v = 0; v < vertices.size(); ++v)
    if (renumber[v] >= 0) mesh.vertices.row(renumber[v]) = vertices[v];
  mesh.triangles.resize(Eigen::Index(triangles.size()), 3);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      mesh.triangles(Eigen::Index(t), c) = renumber[std::size_t(triangles[t][c])];
  return true;
}

}  // namespace sdfcontour

namespace sdfcontour {

void append_mesh(Mesh& mesh, const Mesh& part) {
  const Eigen::Index v = mesh.vertices.rows(), t = mesh.triangles.rows();
  mesh.vertices.conservativeResize(v + part.vertices.rows(), 3);
  mesh.vertices.bottomRows(part.vertices.rows()) = part.vertices;
  mesh.triangles.conservativeResize(t + part.triangles.rows(), 3);
  mesh.triangles.bottomRows(part.triangles.rows()) = part.triangles.array() + int(v);
}

}  // namespace sdfcontour
