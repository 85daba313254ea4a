#include "sdfcontour/extraction/brick_marching.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>

#include "extraction/cube_polygons.h"

namespace sdfcontour {

namespace {

std::string triple(const std::array<int, 3>& a) {
  return "(" + std::to_string(a[0]) + ", " + std::to_string(a[1]) + ", " + std::to_string(a[2]) +
         ")";
}

// Throws Error for a bad brick; returns whether its values change sign (else it has no piece).
bool check_brick(const GridView& block, const GridGeometry& grid, const std::array<int, 3>& first) {
  for (int a = 0; a < 3; ++a) {
    if (grid.dims[a] < 2) throw Error("the grid needs at least 2 samples on every axis");
    if (block.dims[a] < 2) throw Error("a brick needs at least 2 samples on every axis");
    if (first[a] < 0 || long(first[a]) + block.dims[a] > grid.dims[a])
      throw Error("the brick at " + triple(first) + " of " + triple(block.dims) +
                  " samples is not inside the grid of " + triple(grid.dims));
    if (!(grid.bounds.min[a] < grid.bounds.max[a]))
      throw Error("the grid's bounds need min < max on every axis");
  }
  // Keys go up to 7 N: N < 2^61 keeps them in 64 bits.
  const long double n = static_cast<long double>(grid.dims[0]) * grid.dims[1] * grid.dims[2];
  if (n >= static_cast<long double>(std::uint64_t(1) << 61))
    throw Error("the grid has too many samples for 64-bit vertex keys");
  const std::size_t count = block.size();
  return block.visit([&](const auto* f) {
    bool inside = false, outside = false;
    for (std::size_t p = 0; p < count; ++p) {
      (f[p] < 0 ? inside : outside) = true;
      if (!std::isfinite(double(f[p]))) {
        const std::size_t k = p % std::size_t(block.dims[2]),
                          j = p / std::size_t(block.dims[2]) % std::size_t(block.dims[1]),
                          i = p / (std::size_t(block.dims[2]) * std::size_t(block.dims[1]));
        throw Error("the grid has a non-finite value at [" + std::to_string(first[0] + i) + ", " +
                    std::to_string(first[1] + j) + ", " + std::to_string(first[2] + k) + "]");
      }
    }
    return inside && outside;
  });
}

// Collects the brick's vertices by key; ids are provisional until sorted.
class PieceBuilder {
 public:
  int id(std::uint64_t key, const Eigen::Vector3d& position) {
    const auto [it, added] = ids_.try_emplace(key, int(keys_.size()));
    if (added) keys_.push_back(key), positions_.push_back(position);
    return it->second;
  }
  void add_triangle(const std::array<int, 3>& t) { triangles_.push_back(t); }

  MeshPiece finish() {
    std::vector<int> order(keys_.size()), rank(keys_.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return keys_[a] < keys_[b]; });
    MeshPiece piece;
    piece.keys.resize(keys_.size());
    piece.vertices.resize(Eigen::Index(keys_.size()), 3);
    for (std::size_t r = 0; r < order.size(); ++r) {
      rank[std::size_t(order[r])] = int(r);
      piece.keys[r] = keys_[std::size_t(order[r])];
      piece.vertices.row(Eigen::Index(r)) = positions_[std::size_t(order[r])].transpose();
    }
    piece.triangles.resize(Eigen::Index(triangles_.size()), 3);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (int c = 0; c < 3; ++c)
        piece.triangles(Eigen::Index(t), c) = rank[std::size_t(triangles_[t][std::size_t(c)])];
    return piece;
  }

 private:
  std::unordered_map<std::uint64_t, int> ids_;
  std::vector<std::uint64_t> keys_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<std::array<int, 3>> triangles_;
};

template <class Value>
MeshPiece march_brick(const Value* f, const GridView& block, const GridGeometry& grid,
                      const std::array<int, 3>& first) {
  const detail::CubeTables& T = detail::cube_tables();
  const Eigen::Vector3d h = grid.spacing();
  const std::uint64_t samples = grid.size();
  const int bx = block.dims[0], by = block.dims[1], bz = block.dims[2];
  PieceBuilder builder;
  detail::PolygonOutput cube;
  for (int i = 0; i + 1 < bx; ++i)
    for (int j = 0; j + 1 < by; ++j)
      for (int k = 0; k + 1 < bz; ++k) {
        double value[8];
        int mask = 0;
        for (int c = 0; c < 8; ++c) {
          value[c] = f[block.index(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))];
          mask |= (value[c] < 0) << c;
        }
        if (mask == 0 || mask == 255) continue;
        const int I = first[0] + i, J = first[1] + j, K = first[2] + k;
        cube.triangles.clear();
        cube.centroids.clear();
        detail::cube_polygons(value, [&](const int* edges, int size) {
          int polygon[12];
          Eigen::Vector3d position[12];
          for (int q = 0; q < size; ++q) {
            const int c = T.edge_low_corner[edges[q]], a = edges[q] / 4;
            const int pi = I + (c & 1), pj = J + (c >> 1 & 1), pk = K + (c >> 2 & 1);
            // The same formula as marching_cubes: the same bits on both sides of a seam.
            const double fa = value[c], fb = value[c | 1 << a];
            Eigen::Vector3d x = grid.point(pi, pj, pk);
            x[a] += fa / (fa - fb) * h[a];
            polygon[q] =
                builder.id(3 * std::uint64_t(grid.index(pi, pj, pk)) + std::uint64_t(a), x);
            position[q] = x;
          }
          detail::triangulate_polygon(polygon, edges, position, size, cube);
        });
        const std::uint64_t cell = 3 * samples + 4 * std::uint64_t(grid.index(I, J, K));
        std::vector<int> centroid_ids;
        for (std::size_t n = 0; n < cube.centroids.size(); ++n)
          centroid_ids.push_back(builder.id(cell + n, cube.centroids[n]));
        for (auto t : cube.triangles) {
          for (int& v : t)
            if (v < 0) v = centroid_ids[std::size_t(-v - 1)];
          builder.add_triangle(t);
        }
      }
  return builder.finish();
}

}  // namespace

MeshPiece marching_cubes_brick(const GridView& block, const GridGeometry& grid,
                               const std::array<int, 3>& first) {
  if (!check_brick(block, grid, first)) return {};  // one sign: no surface
  return block.visit([&](const auto* f) { return march_brick(f, block, grid, first); });
}

Mesh join_mesh_pieces(const std::vector<MeshPiece>& pieces) {
  std::vector<std::uint64_t> keys;
  for (const MeshPiece& p : pieces) keys.insert(keys.end(), p.keys.begin(), p.keys.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  if (keys.size() > std::size_t(std::numeric_limits<int>::max()))
    throw Error("the mesh has " + std::to_string(keys.size()) +
                " vertices: its int32 indices hold at most 2147483647");
  Mesh mesh;
  mesh.vertices.resize(Eigen::Index(keys.size()), 3);
  std::vector<char> placed(keys.size(), 0);
  Eigen::Index triangles = 0;
  for (const MeshPiece& p : pieces) triangles += p.triangles.rows();
  mesh.triangles.resize(triangles, 3);
  Eigen::Index at = 0;
  for (const MeshPiece& p : pieces) {
    std::vector<int> global(p.keys.size());
    for (std::size_t v = 0; v < p.keys.size(); ++v) {
      const std::size_t g =
          std::size_t(std::lower_bound(keys.begin(), keys.end(), p.keys[v]) - keys.begin());
      global[v] = int(g);
      if (placed[g] && mesh.vertices.row(Eigen::Index(g)) != p.vertices.row(Eigen::Index(v)))
        throw InternalError("two pieces place vertex " + std::to_string(p.keys[v]) +
                            " differently");
      mesh.vertices.row(Eigen::Index(g)) = p.vertices.row(Eigen::Index(v));
      placed[g] = 1;
    }
    for (Eigen::Index t = 0; t < p.triangles.rows(); ++t, ++at)
      for (int c = 0; c < 3; ++c) mesh.triangles(at, c) = global[std::size_t(p.triangles(t, c))];
  }
  return mesh;
}

Mesh marching_cubes(const BlockedGrid& grid, int brick) {
  if (brick < 1) throw Error("the bricks must be at least one cell wide");
  validate_grid_geometry(grid);
  std::vector<MeshPiece> pieces;
  std::vector<float> values;
  const std::array<int, 3> cells{grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1};
  // (A brick's cells [first, end) read samples up to end: grown by one.)
  const std::vector<long> visit = bricks_to_visit(grid, cells, brick, 1);
  for_each_listed_brick(
      cells, brick, visit, [&](long, const std::array<int, 3>& first, std::array<int, 3> end) {
        for (int& e : end) ++e;  // its cells' samples
        if (grid.may_hold_surface && !grid.may_hold_surface(first, end)) return;
        pieces.push_back(marching_cubes_brick(read_block(grid, first, end, values), grid, first));
      });
  return join_mesh_pieces(pieces);
}

}  // namespace sdfcontour
