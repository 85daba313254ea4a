#include "reconstruction/local/surface_cells.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "extraction/cube_polygons.h"

namespace sdfcontour::detail {

std::array<int, 3> corner_of(const std::array<int, 3>& cell, int c) {
  return {cell[0] + (c & 1), cell[1] + (c >> 1 & 1), cell[2] + (c >> 2 & 1)};
}

double value_at(const GridView& grid, const std::array<int, 3>& p) {
  return grid.value(grid.index(p[0], p[1], p[2]));
}

namespace {

// The field's gradient at a sample: central differences, one-sided on the grid's sides.
Eigen::Vector3d gradient_at(const GridView& grid, const std::array<int, 3>& p,
                            const Eigen::Vector3d& h) {
  Eigen::Vector3d g;
  for (int d = 0; d < 3; ++d) {
    std::array<int, 3> lo = p, hi = p;
    lo[d] = std::max(p[d] - 1, 0);
    hi[d] = std::min(p[d] + 1, grid.dims[d] - 1);
    g[d] = (value_at(grid, hi) - value_at(grid, lo)) / ((hi[d] - lo[d]) * h[d]);
  }
  return g;
}

// How many of the samples (i, j, k) and (i + 1, j, k) are negative, per k in [k0, k1], into out.
template <class T>
void negatives_in_pair(const T* row, const T* next_slab_row, int k0, int k1, unsigned char* out) {
  for (int k = k0; k <= k1; ++k)
    out[k - k0] = static_cast<unsigned char>((row[k] < 0) + (next_slab_row[k] < 0));
}

// The cells of slab i (cells (i, *, *)) in the box that the surface crosses, with their
// polygons' edges. Most cells are on one side: their corners' signs alone rule them out, counted
// per row of samples once (a cell's eight loads and tests were 3% of a 512^3 run).
template <class T>
void slab_cells(const SurfaceCells& cells, const T* values, int i, std::vector<ActiveCell>& out) {
  const GridView& grid = cells.grid;
  const auto& n = grid.dims;
  const std::int64_t slab = std::int64_t(i) * (n[1] - 1) * (n[2] - 1);
  const std::size_t sj = std::size_t(n[2]), si = std::size_t(n[1]) * sj;
  const std::size_t offset[8] = {0, si, sj, si + sj, 1, si + 1, sj + 1, si + sj + 1};
  const int k0 = cells.box_lo[2], k1 = cells.box_hi[2];  // cells k0..k1 - 1, samples k0..k1
  if (k0 >= k1) return;
  thread_local std::vector<unsigned char> below_buffer, above_buffer;
  below_buffer.resize(std::size_t(k1 - k0 + 1));
  above_buffer.resize(std::size_t(k1 - k0 + 1));
  unsigned char* below = below_buffer.data();  // row j's pair of slabs
  unsigned char* above = above_buffer.data();  // row j + 1's
  auto row_of = [&](int j) { return values + grid.index(i, j, 0); };
  if (cells.box_lo[1] < cells.box_hi[1])
    negatives_in_pair(row_of(cells.box_lo[1]), row_of(cells.box_lo[1]) + si, k0, k1, below);
  double v[8];
  for (int j = cells.box_lo[1]; j < cells.box_hi[1]; ++j) {
    const T* row = row_of(j);
    negatives_in_pair(row + sj, row + sj + si, k0, k1, above);
    for (int k = k0; k < k1; ++k) {
      const int inside = below[k - k0] + below[k - k0 + 1] + above[k - k0] + above[k - k0 + 1];
      if (inside == 0 || inside == 8) continue;
      const T* at = row + k;
      for (int c = 0; c < 8; ++c) v[c] = double(at[offset[c]]);
      const CubeCase cube = cube_case(v);
      ActiveCell cell;
      cell.key = slab + std::int64_t(j) * (n[2] - 1) + k;
      cell.inside = cube.inside;
      cell.connected = cube.insides_connected;
      cell.polygon_of_edge.fill(-1);
      cube_polygons(cube, [&](const int* edges, int size) {
        for (int e = 0; e < size; ++e)
          cell.polygon_of_edge[std::size_t(edges[e])] = cell.polygon_count;
        ++cell.polygon_count;
      });
      out.push_back(cell);
    }
    std::swap(below, above);
  }
}

}  // namespace

std::array<int, 3> SurfaceCells::cell_of_key(std::int64_t key) const {
  const int k = int(key % cell_dims[2]);
  key /= cell_dims[2];
  return {int(key / cell_dims[1]), int(key % cell_dims[1]), k};
}

std::uint64_t SurfaceCells::global_cell(const std::array<int, 3>& c) const {
  const std::array<int, 3> n = grid.whole_dims();
  return (std::uint64_t(c[0] + first[0]) * std::uint64_t(n[1] - 1) +
          std::uint64_t(c[1] + first[1])) *
             std::uint64_t(n[2] - 1) +
         std::uint64_t(c[2] + first[2]);
}

std::uint64_t SurfaceCells::global_point(const std::array<int, 3>& p) const {
  const std::array<int, 3> n = grid.whole_dims();
  return (std::uint64_t(p[0] + first[0]) * std::uint64_t(n[1]) + std::uint64_t(p[1] + first[1])) *
             std::uint64_t(n[2]) +
         std::uint64_t(p[2] + first[2]);
}

std::int64_t SurfaceCells::key_of_point(const Eigen::Vector3d& p) const {
  std::array<int, 3> c;
  for (int d = 0; d < 3; ++d) {
    // The whole grid's cell, then the block's: the same bin for a point in block and whole.
    const double t = std::floor((p[d] - min[d]) / spacing[d]) - first[std::size_t(d)];
    c[std::size_t(d)] = int(std::clamp(t, 0.0, double(cell_dims[std::size_t(d)] - 1)));
  }
  return key(c);
}

long SurfaceCells::find(std::int64_t k) const {
  const auto it = std::lower_bound(active.begin(), active.end(), k,
                                   [](const ActiveCell& c, std::int64_t x) { return c.key < x; });
  return it != active.end() && it->key == k ? long(it - active.begin()) : -1;
}

CellPolygons SurfaceCells::polygons(const ActiveCell& cell) const {
  const CubeTables& T = cube_tables();
  const std::array<int, 3> at = cell_of_key(cell.key);
  CellPolygons out;
  out.count = cell.polygon_count;
  int next = 0;
  for (int q = 0; q < out.count; ++q) {
    out.first_crossing[std::size_t(q)] = next;
    Eigen::Vector3d outward = Eigen::Vector3d::Zero();
    for (int e = 0; e < 12; ++e) {
      if (cell.polygon_of_edge[std::size_t(e)] != q) continue;
      const int c0 = T.edge_low_corner[e], c1 = c0 | 1 << (e / 4);
      const std::array<int, 3> p0 = corner_of(at, c0), p1 = corner_of(at, c1);
      const double f0 = value_at(grid, p0), f1 = value_at(grid, p1);
      const double t = f0 / (f0 - f1);
      const Eigen::Vector3d x0 = corner(p0), x1 = corner(p1);
      Eigen::Vector3d g =
          (1 - t) * gradient_at(grid, p0, spacing) + t * gradient_at(grid, p1, spacing);
      if (!(g.norm() > 0)) g = Eigen::Vector3d::Unit(e / 4) * (f1 > f0 ? 1 : -1);
      out.crossing[std::size_t(next)] = x0 + t * (x1 - x0);
      out.crossing_normal[std::size_t(next)] = g.normalized();
      outward += g.normalized();
      ++next;
    }
    out.outward[std::size_t(q)] = outward;
  }
  out.first_crossing[std::size_t(out.count)] = next;
  return out;
}

SurfaceCells find_surface_cells(const GridView& grid,
                                const std::array<std::array<int, 3>, 2>* box) {
  SurfaceCells cells;
  cells.grid = grid;
  for (std::size_t d = 0; d < 3; ++d) {
    cells.cell_dims[d] = grid.dims[d] - 1;
    cells.box_lo[d] = box ? std::clamp((*box)[0][d], 0, cells.cell_dims[d]) : 0;
    cells.box_hi[d] =
        box ? std::clamp((*box)[1][d], cells.box_lo[d], cells.cell_dims[d]) : cells.cell_dims[d];
  }
  cells.min = grid.bounds.min;
  cells.spacing = grid.spacing();
  cells.first = grid.first;
  const int i0 = cells.box_lo[0];
  std::vector<std::vector<ActiveCell>> slabs(std::size_t(cells.box_hi[0] - i0));
  tbb::parallel_for(i0, cells.box_hi[0], [&](int i) {
    grid.visit(
        [&](const auto* values) { slab_cells(cells, values, i, slabs[std::size_t(i - i0)]); });
  });
  // Each slab's first cell and first vertex, then the slabs copied in parallel.
  std::vector<std::size_t> first_cell(slabs.size() + 1, 0);
  std::vector<int> first_vertex(slabs.size() + 1, 0);
  for (std::size_t i = 0; i < slabs.size(); ++i) {
    int polygons = 0;
    for (const ActiveCell& c : slabs[i]) polygons += c.polygon_count;
    first_cell[i + 1] = first_cell[i] + slabs[i].size();
    first_vertex[i + 1] = first_vertex[i] + polygons;
  }
  cells.active.resize(first_cell.back());
  tbb::parallel_for(std::size_t(0), slabs.size(), [&](std::size_t i) {
    int next_vertex = first_vertex[i];
    std::size_t at = first_cell[i];
    for (ActiveCell& c : slabs[i]) {
      c.first_vertex = next_vertex;
      next_vertex += c.polygon_count;
      cells.active[at++] = c;
    }
    std::vector<ActiveCell>().swap(slabs[i]);
  });
  return cells;
}

}  // namespace sdfcontour::detail
