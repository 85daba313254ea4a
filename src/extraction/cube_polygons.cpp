#include "extraction/cube_polygons.h"

namespace sdfcontour::detail {

CubeTables::CubeTables() {
  for (auto& r : edge_id) r[0] = r[1] = r[2] = -1;
  for (int a = 0; a < 3; ++a) {
    int rank = 0;
    for (int c = 0; c < 8; ++c)
      if (!(c >> a & 1)) {
        edge_id[c][a] = a * 4 + rank++;
        edge_low_corner[edge_id[c][a]] = c;
      }
  }
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) {
      if (edge_id[c][a] < 0) continue;
      int mask = 0;
      for (int b = 0; b < 3; ++b)
        if (b != a) mask |= 1 << (b * 2 + (c >> b & 1));
      edge_faces[edge_id[c][a]] = mask;
    }
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s) {
      const int u = (a + 1) % 3, v = (a + 2) % 3;
      // (0,0) (1,0) (1,1) (0,1) in (u, v) is counter-clockwise about +a.
      const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int q = 0; q < 4; ++q) {
        const int from = s ? q : (4 - q) % 4;  // reversed on the -a side
        face_corner[a * 2 + s][q] = (s << a) | (uv[from][0] << u) | (uv[from][1] << v);
      }
    }
}

const CubeTables& cube_tables() {
  static const CubeTables tables;
  return tables;
}

void triangulate_polygon(const int* polygon, const int* edges, const Eigen::Vector3d* position,
                         int size, PolygonOutput& out) {
  const CubeTables& T = cube_tables();
  int best_apex = size == 3 ? 0 : -1;
  double best_length = 0;
  for (int a = 0; a < size && size > 3; ++a) {
    bool valid = true;
    double length = 0;
    for (int q = 2; q + 1 < size && valid; ++q) {
      const int j = (a + q) % size;
      valid = !(T.edge_faces[edges[a]] & T.edge_faces[edges[j]]);
      length += (position[j] - position[a]).squaredNorm();
    }
    if (valid && (best_apex < 0 || length < best_length)) best_apex = a, best_length = length;
  }
  if (best_apex >= 0) {
    for (int q = 1; q + 1 < size; ++q)
      out.triangles.push_back({polygon[best_apex], polygon[(best_apex + q) % size],
                               polygon[(best_apex + q + 1) % size]});
    return;
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int q = 0; q < size; ++q) centroid += position[q];
  out.centroids.push_back(centroid / size);
  const int c = -int(out.centroids.size());
  for (int q = 0; q < size; ++q) out.triangles.push_back({c, polygon[q], polygon[(q + 1) % size]});
}

void polygons_to_mesh(const std::vector<PolygonOutput>& parts, Mesh& mesh) {
  std::size_t total = 0, extra = 0;
  for (const auto& s : parts) total += s.triangles.size(), extra += s.centroids.size();
  const Eigen::Index edge_vertices = mesh.vertices.rows();
  mesh.vertices.conservativeResize(edge_vertices + Eigen::Index(extra), 3);
  mesh.triangles.resize(Eigen::Index(total), 3);
  Eigen::Index at = 0, next_centroid = edge_vertices;
  for (const auto& s : parts) {
    for (const auto& c : s.centroids) mesh.vertices.row(next_centroid++) = c.transpose();
    const Eigen::Index base = next_centroid - Eigen::Index(s.centroids.size());
    for (const auto& t : s.triangles) {
      for (int k = 0; k < 3; ++k)
        mesh.triangles(at, k) =
            t[std::size_t(k)] >= 0 ? t[std::size_t(k)] : int(base) - t[std::size_t(k)] - 1;
      ++at;
    }
  }
}

}  // namespace sdfcontour::detail
