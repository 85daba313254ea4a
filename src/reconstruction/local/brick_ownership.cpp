// What a brick of the local reconstruction owns (brick_ownership.h).
#include "reconstruction/local/brick_ownership.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <utility>
#include <vector>

namespace sdfcontour::detail {

Index3 grid_point_of(std::uint64_t p, const Index3& n) {
  const int k = int(p % std::uint64_t(n[2]));
  p /= std::uint64_t(n[2]);
  return {int(p / std::uint64_t(n[1])), int(p % std::uint64_t(n[1])), k};
}

std::uint64_t grid_index_of(const Index3& p, const Index3& n) {
  return (std::uint64_t(p[0]) * std::uint64_t(n[1]) + std::uint64_t(p[1])) * std::uint64_t(n[2]) +
         std::uint64_t(p[2]);
}

Index3 global_sample(const GridGeometry& block, const BandSamples& band, std::size_t s) {
  const Index3 at = grid_point_of(std::uint64_t(band.source[s]), block.dims);
  return {at[0] + block.first[0], at[1] + block.first[1], at[2] + block.first[2]};
}

Index3 edge_low_point(std::uint64_t edge, const Index3& n) {
  return grid_point_of(edge / 3, n);
}

bool in_range(const Index3& p, const Index3& lo, const Index3& hi) {
  for (int a = 0; a < 3; ++a)
    if (p[std::size_t(a)] < lo[std::size_t(a)] || p[std::size_t(a)] >= hi[std::size_t(a)])
      return false;
  return true;
}

// Per triangle t < count: whether the low sample of its grid edge edge_of(t) lies in [lo, hi),
// in parallel (three divisions a triangle).
template <class EdgeOf>
std::vector<char> triangles_in_range(Eigen::Index count, EdgeOf edge_of, const Index3& n,
                                     const Index3& lo, const Index3& hi) {
  std::vector<char> inside(static_cast<std::size_t>(count));
  tbb::parallel_for(Eigen::Index(0), count, [&](Eigen::Index t) {
    inside[std::size_t(t)] = in_range(edge_low_point(edge_of(t), n), lo, hi);
  });
  return inside;
}

detail::KeyedTriangles triangles_of_edges(const detail::KeyedLocalMesh& keyed, const Index3& n,
                                          const Index3& lo, const Index3& hi,
                                          PointMatrix& crossing_means) {
  const Eigen::Index count = keyed.mesh.triangles.rows();
  const std::vector<char> inside = triangles_in_range(
      count, [&](Eigen::Index t) { return keyed.triangle_edge[std::size_t(t)]; }, n, lo, hi);
  // The kept triangles by name, each chunk of triangles packed at its place in parallel.
  constexpr Eigen::Index kChunk = 1 << 14;
  const std::size_t chunks = std::size_t((count + kChunk - 1) / kChunk);
  std::vector<std::size_t> start(chunks + 1, 0);
  for (std::size_t q = 0; q < chunks; ++q)
    start[q + 1] =
        start[q] +
        std::size_t(std::count(inside.begin() + Eigen::Index(q) * kChunk,
                               inside.begin() + std::min(count, Eigen::Index(q + 1) * kChunk), 1));
  std::vector<std::pair<std::uint64_t, Eigen::Index>> kept(start.back());
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t q) {
    std::size_t at = start[q];
    for (Eigen::Index t = Eigen::Index(q) * kChunk;
         t < std::min(count, Eigen::Index(q + 1) * kChunk); ++t)
      if (inside[std::size_t(t)])
        kept[at++] = {keyed.triangle_edge[std::size_t(t)] * 8 + keyed.triangle_rank[std::size_t(t)],
                      t};
  });
  tbb::parallel_sort(kept.begin(), kept.end());  // (distinct names: the same order)
  // Vertices numbered in the order the sorted triangles first name them.
  std::vector<int> id(std::size_t(keyed.mesh.vertices.rows()), -1);
  detail::KeyedTriangles out;
  out.triangles.resize(Eigen::Index(kept.size()), 3);
  out.triangle_name.resize(kept.size());
  std::vector<int> used;
  for (std::size_t r = 0; r < kept.size(); ++r) {
    out.triangle_name[r] = kept[r].first;
    for (int c = 0; c < 3; ++c) {
      const int v = keyed.mesh.triangles(kept[r].second, c);
      if (id[std::size_t(v)] < 0) {
        id[std::size_t(v)] = int(used.size());
        used.push_back(v);
      }
      out.triangles(Eigen::Index(r), c) = id[std::size_t(v)];
    }
  }
  out.vertices.resize(Eigen::Index(used.size()), 3);
  crossing_means.resize(Eigen::Index(used.size()), 3);
  out.vertex_key.resize(used.size());
  out.on_feature.resize(used.size());
  tbb::parallel_for(std::size_t(0), used.size(), [&](std::size_t v) {
    const Eigen::Index u = used[v];
    out.vertices.row(Eigen::Index(v)) = keyed.mesh.vertices.row(u);
    crossing_means.row(Eigen::Index(v)) =
        u < keyed.crossing_means.rows() ? keyed.crossing_means.row(u) : keyed.mesh.vertices.row(u);
    out.vertex_key[v] = keyed.vertex_key[std::size_t(u)];
    out.on_feature[v] = std::size_t(u) < keyed.flags.size() ? keyed.flags[std::size_t(u)][1] : 0;
  });
  return out;
}

LocalReconstructionStats owned_cell_stats(const detail::KeyedLocalMesh& keyed, const Index3& n,
                                          const Index3& own_first, const Index3& own_end) {
  LocalReconstructionStats s;
  const std::uint64_t ny = std::uint64_t(n[1] - 1), nz = std::uint64_t(n[2] - 1);
  for (std::size_t v = 0; v < keyed.flags.size(); ++v) {
    const std::uint64_t cell = keyed.vertex_key[v] / 4;
    const Index3 at{int(cell / (ny * nz)), int(cell / nz % ny), int(cell % nz)};
    if (!in_range(at, own_first, own_end)) continue;
    ++s.vertices;
    // A cell's vertices are keyed 4 * cell + polygon: the first makes a cell, the second a split.
    s.cells += keyed.vertex_key[v] % 4 == 0;
    s.split_cells += keyed.vertex_key[v] % 4 == 1;
    const auto& f = keyed.flags[v];
    s.crossing_cells += f[0], s.feature_vertices += f[1] != 0, s.clamped += f[2];
    s.field_misses += f[3];
  }
  return s;
}

void keep_owned_contact_points(const GridView& block, const BandSamples& band,
                               const ContactPoints& cp, const Index3& own_first,
                               const Index3& own_end, LocalPiece& piece) {
  const Index3 n = block.whole_dims();
  std::vector<std::pair<std::uint64_t, int>> owned;
  for (int q = 0; q < cp.size(); ++q) {
    const Index3 at = global_sample(block, band, std::size_t(cp.samples[std::size_t(q)]));
    if (in_range(at, own_first, own_end)) owned.push_back({grid_index_of(at, n), q});
  }
  std::sort(owned.begin(), owned.end());
  piece.owned_points.resize(Eigen::Index(owned.size()), 3);
  piece.owned_normals.resize(Eigen::Index(owned.size()), 3);
  for (std::size_t r = 0; r < owned.size(); ++r) {
    piece.owned_samples.push_back(owned[r].first);
    piece.owned_points.row(Eigen::Index(r)) = cp.points.row(owned[r].second);
    piece.owned_normals.row(Eigen::Index(r)) = cp.normals.row(owned[r].second);
  }
}

void take_owned_part(const detail::SubdividedMesh& sub, const Index3& n, const Index3& own_first,
                     const Index3& own_end, LocalPiece& piece) {
  const std::vector<char> inside = triangles_in_range(
      sub.mesh.triangles.rows(), [&](Eigen::Index t) { return sub.parent[std::size_t(t)] / 8; }, n,
      own_first, own_end);
  std::vector<Eigen::Index> owned;
  for (Eigen::Index t = 0; t < sub.mesh.triangles.rows(); ++t)
    if (inside[std::size_t(t)]) owned.push_back(t);
  std::vector<int> id(std::size_t(sub.mesh.vertices.rows()), -1);
  for (Eigen::Index t : owned)
    for (int c = 0; c < 3; ++c) id[std::size_t(sub.mesh.triangles(t, c))] = 0;
  int next = 0;
  for (int& v : id)
    if (v == 0) v = next++;
  piece.vertices.resize(next, 3);
  piece.keys.resize(std::size_t(next));
  tbb::parallel_for(std::size_t(0), id.size(), [&](std::size_t v) {
    if (id[v] < 0) return;
    piece.vertices.row(id[v]) = sub.mesh.vertices.row(Eigen::Index(v));
    piece.keys[std::size_t(id[v])] = sub.keys[v];
  });
  piece.triangles.resize(Eigen::Index(owned.size()), 3);
  piece.triangle_names.resize(owned.size());
  tbb::parallel_for(std::size_t(0), owned.size(), [&](std::size_t r) {
    const Eigen::Index t = owned[r];
    piece.triangle_names[r] =
        sub.parent[std::size_t(t)] * 256 + std::uint64_t(sub.child[std::size_t(t)]);
    for (int c = 0; c < 3; ++c)
      piece.triangles(Eigen::Index(r), c) = id[std::size_t(sub.mesh.triangles(t, c))];
  });
}

}  // namespace sdfcontour::detail
