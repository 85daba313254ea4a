#include "system.h"

#include "bspline.h"

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

constexpr int kPairs = 36;  // corner pairs a <= b
int pair_index(int a, int b) {
  if (a > b) std::swap(a, b);
  return a * 8 - a * (a - 1) / 2 + (b - a);
}

// Screening moments per cell holding points: sums of w_a w_b (a <= b) and of w_a over its points,
// w the trilinear weights of the cell's corners; and the cell's corner nodes.
// Both filled by a parallel loop, so not value-initialised first (a serial pass over ~300 bytes
// per cell).
struct ScreeningMoments {
  std::vector<std::array<double, kPairs + 8>,
              UninitialisedAllocator<std::array<double, kPairs + 8>>>
      moments;
  std::vector<std::array<int, 8>, UninitialisedAllocator<std::array<int, 8>>> corners;
};

ScreeningMoments screening_moments(const OctreeLevel& L, const CellRuns& runs,
                                   const std::vector<UnitPoint>& points, const MortonRuns& morton) {
  ScreeningMoments s;
  s.moments.resize(runs.cells.size());
  s.corners.resize(runs.cells.size());
  tbb::parallel_for(std::size_t(0), runs.cells.size(), [&](std::size_t r) {
    auto& m = s.moments[r];
    m.fill(0.0);
    const auto cell = runs.cell(L, r);
    s.corners[r] = L.corner_nodes(cell);
    for (std::uint32_t q = runs.cells[r][1]; q < runs.cells[r][2]; ++q) {
      const UnitPoint& s = points[morton.point(q)];
      const auto w = corner_weights(s.p, cell, L.res);
      for (int a = 0; a < 8; ++a) {
        const double sw = s.weight * w[std::size_t(a)];
        m[std::size_t(kPairs + a)] += sw;
        for (int b = a; b < 8; ++b) m[std::size_t(pair_index(a, b))] += sw * w[std::size_t(b)];
      }
    }
  });
  return s;
}

// b = -(b + finer) on the solved nodes, 0 elsewhere: the right-hand side from the coarser splats'
// divergence b.
void add_finer_and_negate(const std::vector<char>& solved, const std::vector<double>& finer,
                          std::vector<double>& b) {
  tbb::parallel_for(std::size_t(0), b.size(),
                    [&](std::size_t v) { b[v] = solved[v] ? -(b[v] + finer[v]) : 0.0; });
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
  ScreeningMoments screen;
  if (screening > 0) screen = screening_moments(L, runs, points, morton);
  // Nodes with their own row. For a fixed corner the cells' corner nodes are distinct, so one
  // corner at a time writes without races, in the same order whatever the threads.
  S.row_of.assign(nn, -1);
  const std::size_t screened_cells = screen.corners.size();
  for (int a = 0; a < 8; ++a)
    tbb::parallel_for(std::size_t(0), screened_cells, [&](std::size_t r) {
      S.row_of[std::size_t(screen.corners[r][std::size_t(a)])] = 0;
    });
  int own_rows = 0;
  for (std::size_t v = 0; v < nn; ++v) {
    const auto [i, j, k] = unpack(L.nodes[v]);
    S.row_of[v] = solved[v] && (L.on_face(i, j, k) || S.row_of[v] == 0) ? own_rows++ : -1;
  }
  S.rows.resize(static_cast<std::size_t>(own_rows));
  tbb::parallel_for(std::size_t(0), nn, [&](std::size_t v) {
    if (S.row_of[v] < 0) return;
    const auto [i, j, k] = unpack(L.nodes[v]);
    auto& row = S.rows[std::size_t(S.row_of[v])];
    if (L.on_face(i, j, k))
      stiffness_row(L, i, j, k, row);
    else
      row = S.interior_row;  // the same sums, in the same order
  });
  // Screening: (chi(p) - 1/2)^2 for the points in this depth's active cells.
  for (int a = 7; a >= 0; --a)
    tbb::parallel_for(std::size_t(0), screened_cells, [&](std::size_t r) {
      const std::size_t v = std::size_t(screen.corners[r][std::size_t(a)]);
      if (S.row_of[v] < 0) return;
      const auto& m = screen.moments[r];
      auto& row = S.rows[std::size_t(S.row_of[v])];
      S.b[v] += screening * 0.5 * m[std::size_t(kPairs + a)];
      const int ox = -(a & 1), oy = -(a >> 1 & 1), oz = -(a >> 2 & 1);
      for (int q = 0; q < 8; ++q)
        row[std::size_t(slot(ox + (q & 1), oy + (q >> 1 & 1), oz + (q >> 2 & 1)))] +=
            screening * m[std::size_t(pair_index(a, q))];
    });
  return S;
}

}  // namespace sdfcontour::poisson
