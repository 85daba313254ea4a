#include "system.h"

#include "bspline.h"
#include "deterministic_sum.h"

namespace sdfcontour::poisson {

namespace {

// h K summed over node (i, j, k)'s incident cells inside the domain.
void stiffness_row(const OctreeLevel& L, long i, long j, long k, std::array<double, 27>& row) {
  const TrilinearStiffness& K = trilinear_stiffness();
  row.fill(0.0);
  for (int c = 0; c < 8; ++c) {  // incident cells: offsets -1/0 per axis
    const int ox = (c & 1) - 1, oy = (c >> 1 & 1) - 1, oz = (c >> 2 & 1) - 1;
    if (i + ox < 0 || j + oy < 0 || k + oz < 0 || i + ox >= L.res || j + oy >= L.res ||
        k + oz >= L.res)
      continue;
    const int a = (-ox) | (-oy) << 1 | (-oz) << 2;  // the node's corner in that cell
    for (int corner = 0; corner < 8; ++corner)
      row[std::size_t(slot(ox + (corner & 1), oy + (corner >> 1 & 1), oz + (corner >> 2 & 1)))] +=
          L.h * K.entry[a][corner];
  }
}

// b = -(b + finer) on the solved nodes, 0 elsewhere: the right-hand side from the coarser splats'
// divergence b.
void add_finer_and_negate(const std::vector<char>& solved, const std::vector<double>& finer,
                          std::vector<double>& b) {
  tbb::parallel_for(std::size_t(0), b.size(),
                    [&](std::size_t v) { b[v] = solved[v] ? -(b[v] + finer[v]) : 0.0; });
}

int parity(const std::array<long, 3>& c) {
  return int(c[0] & 1) | int(c[1] & 1) << 1 | int(c[2] & 1) << 2;
}

// out = (stiffness) in on the solved nodes, 0 elsewhere. Every in-domain neighbour of a solved
// node exists (its incident cells are active): (i + dx, j + dy, k + dz) sits at dz from
// (i + dx, j + dy, k), found by a cursor on that node line (no stored neighbour table: at depth
// 10 it would be 36 bytes per node).
void stiffness_product(const OctreeLevel& L, const std::vector<char>& solved, const LevelSystem& S,
                       const std::vector<double>& in, std::vector<double>& out) {
  const double kCentre = S.interior_row[13], kEdge = S.interior_row[std::size_t(slot(1, 1, 0))],
               kCorner = S.interior_row[std::size_t(slot(1, 1, 1))];
  for_each_line(L.node_lines, L.nodes, [&](long i, long j, std::size_t first, std::size_t last) {
    LineCursor neighbours[9];
    for (int t = 0; t < 9; ++t)
      neighbours[t] = LineCursor(L.nodes, L.node_lines.line(i + t % 3 - 1, j + t / 3 - 1));
    int column[9];
    long previous_k = -2;  // of the last solved node
    const bool line_on_face = i == 0 || j == 0 || i == L.res || j == L.res;
    for (std::size_t v = first; v < last; ++v) {
      if (!solved[v]) {
        out[v] = 0;
        continue;
      }
      const long k = long(L.nodes[v] & kKeyMask);
      // Right after a solved node at k - 1, each neighbour is the node after that one's.
      if (k == previous_k + 1)
        for (int t = 0; t < 9; ++t) column[t] += column[t] >= 0;
      else
        for (int t = 0; t < 9; ++t)
          column[t] = neighbours[t].find(pack(i + t % 3 - 1, j + t / 3 - 1, k));
      previous_k = k;
      double sum = 0;
      if (!line_on_face && k > 0 && k < L.res) {
        // Interior: all 27 neighbours exist, and the trilinear stiffness stencil is zero on the
        // six face neighbours, one value on the twelve edge and another on the eight corner
        // neighbours.
        const double* x = in.data();
        double edges = 0, corners = 0;
        for (int t : {0, 2, 6, 8}) {
          const int m = column[t];
          edges += x[m];
          corners += x[m - 1] + x[m + 1];
        }
        for (int t : {1, 3, 5, 7}) {
          const int m = column[t];
          edges += x[m - 1] + x[m + 1];
        }
        sum = kCentre * x[v] + kEdge * edges + kCorner * corners;
      } else {
        std::array<double, 27> row;
        stiffness_row(L, i, j, k, row);
        for (int dz = k > 0 ? -1 : 0; dz <= (k < L.res ? 1 : 0); ++dz)
          for (int t = 0; t < 9; ++t)
            if (column[t] >= 0)
              sum += row[std::size_t(t + 9 * (dz + 1))] * in[std::size_t(column[t] + dz)];
      }
      out[v] = sum;
    }
  });
}

}  // namespace

std::vector<double> splat_divergence(const OctreeLevel& L, const std::vector<char>& solved,
                                     const CellGrid& grid,
                                     const std::vector<Eigen::Vector3d>& coarser,
                                     const std::vector<double>& finer) {
  std::vector<double> b(L.nodes.size(), 0.0);
  divergence(L, grid, coarser, b, &solved);
  add_finer_and_negate(solved, finer, b);
  return b;
}

std::vector<double> splat_divergence_from_coarser(const OctreeLevel& L,
                                                  const std::vector<char>& solved,
                                                  const CellGrid& coarser_grid,
                                                  const std::vector<Eigen::Vector3d>& coarser,
                                                  const std::vector<double>& finer) {
  std::vector<double> b(L.nodes.size(), 0.0);
  // Sixteen slabs: each prolongs about a sixteenth of the grid (plus its 3-row margin).
  const long thickness = std::max(8L, (L.res + 1) / 16);
  for (long first = 0; first <= L.res; first += thickness) {
    const long last = std::min(first + thickness, L.res + 1);
    const CellGrid slab = spline_grid(L, first - 2, last);
    divergence(L, slab, prolong_splines(coarser_grid, slab, coarser), b, &solved, {first, last});
  }
  add_finer_and_negate(solved, finer, b);
  return b;
}

LevelSystem assemble_system(const OctreeLevel& L, const std::vector<char>& solved,
                            std::vector<double> b, const CellRuns& runs, double screening,
                            const std::vector<UnitPoint>& points, const MortonRuns& morton) {
  const std::size_t nn = L.nodes.size();
  LevelSystem S;
  S.b = std::move(b);
  stiffness_row(L, 1, 1, 1, S.interior_row);  // res >= 2, so (1, 1, 1) is off every face
  S.screening = screening;
  // Per cell holding points: its corners, the block of w_a w_b sums, and (for the right-hand side)
  // the sums of w_a.
  const std::size_t cells = screening > 0 ? runs.cells.size() : 0;
  S.screened_corners.resize(cells);
  S.screened_blocks.resize(cells);
  std::vector<std::array<double, 8>, UninitialisedAllocator<std::array<double, 8>>> sums(cells);
  // Grouped by parity (a counting sort, each group in key order).
  std::vector<std::size_t> at(cells);
  for (std::size_t r = 0; r < cells; ++r)
    ++S.parity_begin[std::size_t(parity(runs.cell(L, r))) + 1];
  for (std::size_t g = 1; g < 9; ++g) S.parity_begin[g] += S.parity_begin[g - 1];
  {
    auto next = S.parity_begin;
    for (std::size_t r = 0; r < cells; ++r) at[r] = next[std::size_t(parity(runs.cell(L, r)))]++;
  }
  tbb::parallel_for(std::size_t(0), cells, [&](std::size_t run) {
    const std::size_t r = at[run];
    auto& block = S.screened_blocks[r];
    auto& sum = sums[r];
    block.fill(0.0);
    sum.fill(0.0);
    const auto cell = runs.cell(L, run);
    S.screened_corners[r] = L.corner_nodes(cell);
    for (std::uint32_t q = runs.cells[run][1]; q < runs.cells[run][2]; ++q) {
      const UnitPoint& s = points[morton.point(q)];
      const auto w = corner_weights(s.p, cell, L.res);
      for (int a = 0; a < 8; ++a) {
        const double sw = s.weight * w[std::size_t(a)];
        sum[std::size_t(a)] += sw;
        for (int c = a; c < 8; ++c) block[std::size_t(pair_index(a, c))] += sw * w[std::size_t(c)];
      }
    }
  });
  // Nodes with their own diagonal: solved, on a face or a screened cell's corner. For a fixed
  // corner the cells' corner nodes are distinct, so one corner at a time writes without races, in
  // the same order whatever the threads.
  S.own_of.assign(nn, -1);
  for (int a = 0; a < 8; ++a)
    tbb::parallel_for(std::size_t(0), cells, [&](std::size_t r) {
      S.own_of[std::size_t(S.screened_corners[r][std::size_t(a)])] = 0;
    });
  int own = 0;
  for (std::size_t v = 0; v < nn; ++v) {
    const auto [i, j, k] = unpack(L.nodes[v]);
    S.own_of[v] = solved[v] && (L.on_face(i, j, k) || S.own_of[v] == 0) ? own++ : -1;
  }
  S.own_diagonal.resize(std::size_t(own));
  tbb::parallel_for(std::size_t(0), nn, [&](std::size_t v) {
    if (S.own_of[v] < 0) return;
    const auto [i, j, k] = unpack(L.nodes[v]);
    double centre = S.interior_row[13];
    if (L.on_face(i, j, k)) {
      std::array<double, 27> row;
      stiffness_row(L, i, j, k, row);
      centre = row[13];
    }
    S.own_diagonal[std::size_t(S.own_of[v])] = centre;
  });
  // Screening: (chi(p) - 1/2)^2 for the points in this depth's active cells.
  for (int a = 7; a >= 0; --a)
    tbb::parallel_for(std::size_t(0), cells, [&](std::size_t r) {
      const std::size_t v = std::size_t(S.screened_corners[r][std::size_t(a)]);
      if (S.own_of[v] < 0) return;
      S.b[v] += screening * 0.5 * sums[r][std::size_t(a)];
      S.own_diagonal[std::size_t(S.own_of[v])] +=
          screening * S.screened_blocks[r][std::size_t(pair_index(a, a))];
    });
  return S;
}

double multiply(const OctreeLevel& L, const std::vector<char>& solved, const LevelSystem& S,
                const std::vector<double>& in, std::vector<double>& out) {
  stiffness_product(L, solved, S, in, out);
  // Screening, cell by cell: each corner gets its row of the cell's block times the corners'
  // values. One parity group at a time, so that no two cells write one node at once, and every
  // node sums its (at most one per group) cells in the same order whatever the threads.
  static constexpr auto kPair = [] {
    std::array<std::array<int, 8>, 8> t{};
    for (int a = 0; a < 8; ++a)
      for (int c = 0; c < 8; ++c) t[std::size_t(a)][std::size_t(c)] = pair_index(a, c);
    return t;
  }();
  for (std::size_t g = 0; g < 8; ++g)
    tbb::parallel_for(S.parity_begin[g], S.parity_begin[g + 1], [&](std::size_t r) {
      const auto& corner = S.screened_corners[r];
      const auto& block = S.screened_blocks[r];
      double x[8];
      for (int c = 0; c < 8; ++c) x[c] = in[std::size_t(corner[std::size_t(c)])];
      for (int a = 0; a < 8; ++a) {
        const std::size_t v = std::size_t(corner[std::size_t(a)]);
        if (!solved[v]) continue;
        double sum = 0;
        for (int c = 0; c < 8; ++c)
          sum += block[std::size_t(kPair[std::size_t(a)][std::size_t(c)])] * x[c];
        out[v] += S.screening * sum;
      }
    });
  return deterministic_sum(L.nodes.size(),
                           [&](std::size_t v) { return solved[v] ? in[v] * out[v] : 0.0; });
}

}  // namespace sdfcontour::poisson
