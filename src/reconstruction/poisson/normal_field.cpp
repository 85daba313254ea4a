#include "reconstruction/poisson/normal_field.h"

#include <type_traits>

#include "reconstruction/poisson/bspline.h"

namespace sdfcontour::poisson {

CellRuns cell_runs(const OctreeLevel& L, const MortonRuns& runs) {
  CellRuns out;
  runs.for_each_run(
      L.depth, [&](const std::array<long, 3>& c, std::size_t first, std::size_t last) {
        const int idx = L.cell(pack(c[0], c[1], c[2]));
        if (idx >= 0)
          out.cells.push_back({std::uint32_t(idx), std::uint32_t(first), std::uint32_t(last)});
      });
  return out;
}

namespace {

// The share of point s's normal splatted at depth d.
double splat_share(const UnitPoint& s, int d) {
  return s.depth == d ? 1 - s.finer_share : s.depth + 1 == d ? s.finer_share : 0.0;
}

// The depth-d splat coefficients on the cells they touch (G), each gathered from the points of the
// 27 cells around it (no per-cell table of 27 sums: 648 bytes per cell holding points, 1.2 GB for
// bunny 512^3's depth 10, and filling it took longer than the gather).
void splat_depth(const OctreeLevel& L, const CellRuns& runs, const std::vector<UnitPoint>& points,
                 const MortonRuns& morton, CellGrid& G, std::vector<Eigen::Vector3d>& V) {
  const int d = L.depth;
  std::vector<char> has_splat(runs.cells.size(), 0);
  const double inverse_volume = 1.0 / (L.h * L.h * L.h);
  tbb::parallel_for(std::size_t(0), runs.cells.size(), [&](std::size_t r) {
    for (std::uint32_t q = runs.cells[r][1]; q < runs.cells[r][2] && !has_splat[r]; ++q)
      has_splat[r] = splat_share(points[morton.point(q)], d) > 0;
  });
  // Source cell r's splats on the cell (dx, dy, dz) away, summed over its points in order.
  auto splat_of = [&](std::uint32_t r, int dx, int dy, int dz) {
    const auto cell = runs.cell(L, r);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::uint32_t q = runs.cells[r][1]; q < runs.cells[r][2]; ++q) {
      const UnitPoint& s = points[morton.point(q)];
      const double share = splat_share(s, d);
      if (share == 0) continue;
      double w[3];
      const int offset[3] = {dx, dy, dz};
      for (int a = 0; a < 3; ++a)
        w[a] = quadratic_weights(std::clamp(s.p[a] * double(L.res) - double(cell[std::size_t(a)]),
                                            0.0, 1.0))[std::size_t(offset[a] + 1)];
      const Eigen::Vector3d weighted = share * s.area * s.weight * inverse_volume * s.n;
      sum += w[0] * w[1] * w[2] * weighted;
    }
    return sum;
  };
  // The cells holding depth-d splats, sorted, with their runs.
  std::vector<std::pair<Key, std::uint32_t>> splatting;
  for (std::size_t r = 0; r < runs.cells.size(); ++r)
    if (has_splat[r]) splatting.push_back({L.cells[runs.cells[r][0]], std::uint32_t(r)});
  tbb::parallel_sort(splatting.begin(), splatting.end());
  std::vector<Key> source(splatting.size());
  for (std::size_t t = 0; t < source.size(); ++t) source[t] = splatting[t].first;
  const LineIndex source_lines(source);
  // The cells they touch: each shifted by -1..1 per axis, i.e. by 0..2 in offset (+1) keys.
  G.keys = shifted_union(source, {0, 0, 0}, {2, 2, 2}, L.res + 1);
  G.lines = LineIndex(G.keys);
  V.assign(G.keys.size(), Eigen::Vector3d::Zero());
  // Each cell gathers, offset by offset in slot order, the sum of the source cell that offset
  // away: a fixed order whatever the threads. Source lines are walked with cursors.
  for_each_line(G.lines, G.keys, [&](long gi, long gj, std::size_t first, std::size_t last) {
    LineCursor from[9];  // source line (gi - 1 - dx, gj - 1 - dy) at (dx + 1) + 3 (dy + 1)
    for (int t = 0; t < 9; ++t)
      from[t] = LineCursor(source, source_lines.line(gi - 1 - (t % 3 - 1), gj - 1 - (t / 3 - 1)));
    for (std::size_t g = first; g < last; ++g) {
      const long gk = long(G.keys[g] & kKeyMask);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int t = (dx + 1) + 3 * (dy + 1);
            if (gk - 1 - dz < 0) continue;
            const int at = from[t].find(pack(gi - 1 - dx, gj - 1 - dy, gk - 1 - dz));
            if (at >= 0) sum += splat_of(splatting[std::size_t(at)].second, dx, dy, dz);
          }
      V[g] = sum;
    }
  });
}

// e[v] += the restriction of the finer depth's finer-splat divergence: a depth-d hat is the sum of
// depth-(d+1) hats with weights 1/2, 1, 1/2 per axis. (Where a finer node is missing, the field
// from finer splats is zero there: every finer splat lies inside the finer band.)
void restrict_divergence(const OctreeLevel& L, const OctreeLevel& F,
                         const std::vector<double>& fine, std::vector<double>& e) {
  for_each_line(L.node_lines, L.nodes, [&](long i, long j, std::size_t first, std::size_t last) {
    LineCursor column[9];
    for (int t = 0; t < 9; ++t)
      column[t] = LineCursor(F.nodes, F.node_lines.line(2 * i + t % 3 - 1, 2 * j + t / 3 - 1));
    for (std::size_t v = first; v < last; ++v) {
      const long k = long(L.nodes[v] & kKeyMask);
      double sum = e[v];
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if (2 * k + dz < 0) continue;
            const int u =
                column[dx + 1 + 3 * (dy + 1)].find(pack(2 * i + dx, 2 * j + dy, 2 * k + dz));
            if (u >= 0)
              sum += (1 - 0.5 * std::abs(dx)) * (1 - 0.5 * std::abs(dy)) *
                     (1 - 0.5 * std::abs(dz)) * fine[std::size_t(u)];
          }
      e[v] = sum;
    }
  });
}

}  // namespace

CellGrid spline_grid(const OctreeLevel& L) {
  return spline_grid(L, -1, L.res);  // every index a grid cell can have
}

CellGrid spline_grid(const OctreeLevel& L, long first, long last) {
  // The active cells within two of [first, last] make those grid cells (and a few more, dropped);
  // the whole level is used in place.
  const auto from =
      std::lower_bound(L.cells.begin(), L.cells.end(), pack(std::max(first - 2, 0L), 0, 0));
  const auto to = std::lower_bound(L.cells.begin(), L.cells.end(), pack(last + 3, 0, 0));
  const bool whole = from == L.cells.begin() && to == L.cells.end();
  std::vector<Key> part;
  if (!whole) part.assign(from, to);
  const std::vector<Key>& cells = whole ? L.cells : part;
  CellGrid G;
  // Keys offset by +1: the cells shifted by -1..3 along each axis hold cells -2..+2 around them.
  G.keys = shifted_union(cells, {-1, -1, -1}, {3, 3, 3}, L.res + 1);
  const auto keep_from =
      std::lower_bound(G.keys.begin(), G.keys.end(), pack(std::max(first + 1, 0L), 0, 0));
  const auto keep_to = std::lower_bound(G.keys.begin(), G.keys.end(), pack(last + 2, 0, 0));
  if (keep_from != G.keys.begin() || keep_to != G.keys.end())
    G.keys = std::vector<Key>(keep_from, keep_to);
  G.lines = LineIndex(G.keys);
  return G;
}

void add_on_grid(const CellGrid& cells, const std::vector<Eigen::Vector3d>& values,
                 const CellGrid& grid, std::vector<Eigen::Vector3d>& onto) {
  if (grid.keys.empty()) return;
  // Both key lists are sorted: one merge walk over the cells within the grid's key range.
  const auto from = std::lower_bound(cells.keys.begin(), cells.keys.end(), grid.keys.front());
  const auto to = std::upper_bound(from, cells.keys.end(), grid.keys.back());
  for (std::size_t a = std::size_t(from - cells.keys.begin()), g = 0;
       a < std::size_t(to - cells.keys.begin()); ++a) {
    while (grid.keys[g] < cells.keys[a]) ++g;
    onto[g] += values[a];
  }
}

NormalField splat_normals(const Octree& tree, const std::vector<UnitPoint>& points,
                          const MortonRuns& runs, const std::atomic<bool>* cancel,
                          bool hat_divergence) {
  const std::size_t depths = tree.levels.size();
  NormalField field;
  field.splat_cells.resize(depths);
  field.splat.resize(depths);
  field.finer.resize(depths);
  field.runs.resize(depths);
  // Fine to coarse: finer[d] = S_d(V_d) + restriction of finer[d + 1].
  for (int d = tree.finest; d >= tree.min_depth; --d) {
    check_cancel(cancel);
    const OctreeLevel& L = tree.level(d);
    field.runs[std::size_t(d)] = cell_runs(L, runs);
    const CellGrid& G = field.splat_cells[std::size_t(d)];
    splat_depth(L, field.runs[std::size_t(d)], points, runs, field.splat_cells[std::size_t(d)],
                field.splat[std::size_t(d)]);
    if (!hat_divergence) continue;
    auto& e = field.finer[std::size_t(d)];
    e.assign(L.nodes.size(), 0.0);
    if (!G.keys.empty()) divergence(L, G, field.splat[std::size_t(d)], e, nullptr);
    if (d < tree.finest)
      restrict_divergence(L, tree.level(d + 1), field.finer[std::size_t(d + 1)], e);
  }
  return field;
}

template <class T>
std::vector<T> prolong_splines(const CellGrid& coarse, const CellGrid& fine,
                               const std::vector<T>& values) {
  // Q_c = (Q_{2c-1} + 3 Q_{2c} + 3 Q_{2c+1} + Q_{2c+2}) / 4 per axis.
  T zero;
  if constexpr (std::is_same_v<T, double>)
    zero = 0.0;
  else
    zero = T::Zero();
  std::vector<T> out(fine.keys.size(), zero);
  auto parents = [](long offset_index, long* parent, double* weight) {
    const long index = offset_index - 1, m = index >> 1;  // floor(index / 2)
    parent[0] = m, weight[0] = 0.75;
    parent[1] = (index & 1) ? m + 1 : m - 1, weight[1] = 0.25;
  };
  // A fine line at a time, with cursors on the four coarse lines it reads.
  for_each_line(fine.lines, fine.keys, [&](long i, long j, std::size_t first, std::size_t last) {
    long parent[3][2];
    double weight[3][2];
    parents(i, parent[0], weight[0]);
    parents(j, parent[1], weight[1]);
    LineCursor column[4];
    for (int c = 0; c < 4; ++c)
      column[c] =
          LineCursor(coarse.keys, coarse.lines.line(parent[0][c & 1] + 1, parent[1][c >> 1] + 1));
    for (std::size_t f = first; f < last; ++f) {
      parents(long(fine.keys[f] & kKeyMask), parent[2], weight[2]);
      T sum = zero;
      for (int c = 0; c < 8; ++c) {
        const long pz = parent[2][c >> 2 & 1];
        if (pz < -1) continue;
        const int idx =
            column[c & 3].find(pack(parent[0][c & 1] + 1, parent[1][c >> 1 & 1] + 1, pz + 1));
        if (idx >= 0)
          sum += weight[0][c & 1] * weight[1][c >> 1 & 1] * weight[2][c >> 2 & 1] *
                 values[std::size_t(idx)];
      }
      out[f] = sum;
    }
  });
  return out;
}

template std::vector<Eigen::Vector3d> prolong_splines(const CellGrid&, const CellGrid&,
                                                      const std::vector<Eigen::Vector3d>&);
template std::vector<double> prolong_splines(const CellGrid&, const CellGrid&,
                                             const std::vector<double>&);

void divergence(const OctreeLevel& L, const CellGrid& G, const std::vector<Eigen::Vector3d>& W,
                std::vector<double>& out, const std::vector<char>* want, std::array<long, 2> rows,
                int up) {
  // Over the 4 x 4 x 4 cells whose B-splines overlap node v's hat. The integrals are products of
  // 1D ones, so a line of nodes (fixed i, j) first folds its 16 cell columns into two values per
  // cell height k', P(k') (the x and y terms) and Q(k') (the z term), and each node then sums
  // four heights.
  const HatQuadraticIntegrals I(L.res, up);
  for_each_line(L.node_lines, L.nodes, [&](long i, long j, std::size_t first, std::size_t last) {
    if (i < rows[0] || i >= rows[1]) return;
    // Heights k' = (k_first >> up) - 2 .. (k_last >> up) + 1, stored from index 0.
    const long k_last = long(L.nodes[last - 1] & kKeyMask) >> up;
    const long k_first = long(L.nodes[first] & kKeyMask) >> up, base = k_first - 2;
    std::vector<double> P(std::size_t(k_last - k_first + 4), 0.0), Q(P.size(), 0.0);
    const auto &vx = I.value[std::size_t(i)], &vy = I.value[std::size_t(j)];
    const auto &sx = I.slope[std::size_t(i)], &sy = I.slope[std::size_t(j)];
    for (int c = 0; c < 16; ++c) {
      const long ci = (i >> up) + (c & 3) - 2, cj = (j >> up) + (c >> 2) - 2;
      if (ci < -1 || cj < -1) continue;
      const int ox = c & 3, oy = c >> 2;
      const double px = sx[std::size_t(ox)] * vy[std::size_t(oy)],
                   py = vx[std::size_t(ox)] * sy[std::size_t(oy)],
                   qz = vx[std::size_t(ox)] * vy[std::size_t(oy)];
      const auto range = G.lines.line(ci + 1, cj + 1);
      // Offset keys hold k' + 1.
      const Key prefix = pack(ci + 1, cj + 1, 0), lo = prefix + Key(std::max(base + 1, 0L));
      std::uint32_t u =
          std::uint32_t(std::lower_bound(G.keys.begin() + range[0], G.keys.begin() + range[1], lo) -
                        G.keys.begin());
      for (; u < range[1] && long(G.keys[u] - prefix) - 1 <= k_last + 1; ++u) {
        const std::size_t at = std::size_t(long(G.keys[u] - prefix) - 1 - base);
        P[at] += px * W[u].x() + py * W[u].y();
        Q[at] += qz * W[u].z();
      }
    }
    for (std::size_t v = first; v < last; ++v) {
      if (want && !(*want)[v]) continue;
      const long k = long(L.nodes[v] & kKeyMask);
      const auto &vz = I.value[std::size_t(k)], &sz = I.slope[std::size_t(k)];
      double sum = 0;
      for (int oz = 0; oz < 4; ++oz) {
        const std::size_t at = std::size_t((k >> up) - 2 + oz - base);
        sum += P[at] * vz[std::size_t(oz)] + Q[at] * sz[std::size_t(oz)];
      }
      out[v] += sum;
    }
  });
}

}  // namespace sdfcontour::poisson
