#include "reconstruction/poisson/system.h"

#include "reconstruction/poisson/bspline.h"
#include "reconstruction/poisson/deterministic_sum.h"

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

// b = -b on the solved nodes, 0 elsewhere: b held the finer splats' part plus the coarser ones'
// divergence.
void negate_on_solved(const std::vector<char>& solved, std::vector<double>& b) {
  tbb::parallel_for(std::size_t(0), b.size(),
                    [&](std::size_t v) { b[v] = solved[v] ? -b[v] : 0.0; });
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
                                     std::vector<double> finer) {
  std::vector<double> b = std::move(finer);  // the divergence adds onto it
  divergence(L, grid, coarser, b, &solved);
  negate_on_solved(solved, b);
  return b;
}

std::vector<double> splat_divergence_from_coarser(const OctreeLevel& L,
                                                  const std::vector<char>& solved,
                                                  const CellGrid& coarser_grid,
                                                  const std::vector<Eigen::Vector3d>& coarser,
                                                  std::vector<double> finer,
                                                  const MiddleDepth* middle) {
  std::vector<double> b = std::move(finer);  // the divergence adds onto it
  if (!middle) {
    divergence(L, coarser_grid, coarser, b, &solved, {0, kAllRows}, /*up=*/1);
  } else {
    // Sixteen slabs of node rows: each prolongs about a sixteenth of the middle depth's grid.
    const long thickness = std::max(8L, (L.res + 1) / 16);
    for (long first = 0; first <= L.res; first += thickness) {
      const long last = std::min(first + thickness, L.res + 1);
      const CellGrid between = spline_grid(middle->level, (first >> 1) - 2, ((last - 1) >> 1) + 1);
      std::vector<Eigen::Vector3d> values = prolong_splines(coarser_grid, between, coarser);
      add_on_grid(middle->splat_cells, middle->splat, between, values);
      divergence(L, between, values, b, &solved, {first, last}, /*up=*/1);
    }
  }
  negate_on_solved(solved, b);
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
  // Per cell holding points: its corners and its points' corner weights.
  const std::size_t cells = screening > 0 ? runs.cells.size() : 0;
  S.screened_corners.resize(cells);
  S.point_begin.resize(cells + 1);
  // Grouped by parity, each group in key order.
  const std::vector<std::size_t> at = group_order<8>(
      cells, [&](std::size_t r) { return parity(runs.cell(L, r)); }, S.parity_begin);
  S.point_begin[0] = 0;
  for (std::size_t run = 0; run < cells; ++run)
    S.point_begin[at[run] + 1] = runs.cells[run][2] - runs.cells[run][1];
  for (std::size_t r = 0; r < cells; ++r) S.point_begin[r + 1] += S.point_begin[r];
  S.screened_points.resize(S.point_begin[cells]);
  tbb::parallel_for(std::size_t(0), cells, [&](std::size_t run) {
    const std::size_t r = at[run];
    const auto cell = runs.cell(L, run);
    S.screened_corners[r] = L.corner_nodes(cell);
    auto* out = &S.screened_points[S.point_begin[r]];
    for (std::uint32_t q = runs.cells[run][1]; q < runs.cells[run][2]; ++q, ++out) {
      const UnitPoint& s = points[morton.point(q)];
      *out = {corner_weights(s.p, cell, L.res), s.weight};
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
      double sum = 0, square_sum = 0;
      for (std::uint32_t q = S.point_begin[r]; q < S.point_begin[r + 1]; ++q) {
        const auto& point = S.screened_points[q];
        const double w = point.corner_weight[std::size_t(a)];
        sum += point.weight * w;
        square_sum += point.weight * w * w;
      }
      S.b[v] += screening * 0.5 * sum;
      S.own_diagonal[std::size_t(S.own_of[v])] += screening * square_sum;
    });
  return S;
}

double multiply(const OctreeLevel& L, const std::vector<char>& solved, const LevelSystem& S,
                const std::vector<double>& in, std::vector<double>& out) {
  stiffness_product(L, solved, S, in, out);
  // Screening, cell by cell: each point adds  w_p phi_a(p) chi(p)  to its cell's corners a. One
  // parity group at a time, so that no two cells write one node at once, and every node sums its
  // (at most one per group) cells in the same order whatever the threads.
  for (std::size_t g = 0; g < 8; ++g)
    tbb::parallel_for(S.parity_begin[g], S.parity_begin[g + 1], [&](std::size_t r) {
      const auto& corner = S.screened_corners[r];
      double x[8], sum[8] = {};
      for (int c = 0; c < 8; ++c) x[c] = in[std::size_t(corner[std::size_t(c)])];
      for (std::uint32_t q = S.point_begin[r]; q < S.point_begin[r + 1]; ++q) {
        const auto& w = S.screened_points[q].corner_weight;
        double chi = 0;
        for (int c = 0; c < 8; ++c) chi += w[std::size_t(c)] * x[c];
        chi *= S.screened_points[q].weight;
        for (int a = 0; a < 8; ++a) sum[a] += w[std::size_t(a)] * chi;
      }
      for (int a = 0; a < 8; ++a) {
        const std::size_t v = std::size_t(corner[std::size_t(a)]);
        if (solved[v]) out[v] += S.screening * sum[a];
      }
    });
  return deterministic_sum(L.nodes.size(),
                           [&](std::size_t v) { return solved[v] ? in[v] * out[v] : 0.0; });
}

}  // namespace sdfcontour::poisson
