#include "sdfcontour/contact_points/triangulation.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_3.h>
#include <CGAL/Spatial_lock_grid_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <iterator>
#include <utility>

namespace sdfcontour {

namespace {

// Fills neighbour_* and incident_* from `tets` for `sample_count` samples.
void build_adjacency(Triangulation& triangulation, int sample_count);

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Lock = CGAL::Spatial_lock_grid_3<CGAL::Tag_priority_blocking>;

template <class Concurrency>
struct RegularTypes {
  using Vb = CGAL::Triangulation_vertex_base_with_info_3<
      int, Kernel, CGAL::Regular_triangulation_vertex_base_3<Kernel>>;
  using Cb =
      CGAL::Regular_triangulation_cell_base_3<Kernel, CGAL::Triangulation_cell_base_3<Kernel>,
                                              CGAL::Discard_hidden_points>;
  using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb, Concurrency>;
  using Tr = CGAL::Regular_triangulation_3<
      Kernel, Tds,
      std::conditional_t<std::is_same_v<Concurrency, CGAL::Parallel_tag>, Lock, CGAL::Default>>;
};

template <class Concurrency>
struct DelaunayTypes {
  using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, Kernel>;
  using Cb = CGAL::Delaunay_triangulation_cell_base_3<Kernel>;
  using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb, Concurrency>;
  using Tr = CGAL::Delaunay_triangulation_3<
      Kernel, Tds, CGAL::Default,
      std::conditional_t<std::is_same_v<Concurrency, CGAL::Parallel_tag>, Lock, CGAL::Default>>;
};

// Rotates a positively oriented tet by an even permutation so that its smallest index comes
// first and its second smallest second, which keeps the orientation and makes the row canonical.
std::array<int, 4> canonical_tet(std::array<int, 4> t) {
  const int m = int(std::min_element(t.begin(), t.end()) - t.begin());
  // Even permutations moving position m to 0.
  static const int moves[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
  std::array<int, 4> r{t[moves[m][0]], t[moves[m][1]], t[moves[m][2]], t[moves[m][3]]};
  // Cyclic rotations of the last three are even too.
  while (!(r[1] < r[2] && r[1] < r[3])) std::rotate(r.begin() + 1, r.begin() + 2, r.end());
  return r;
}

// The tets in lexicographic order (a canonical order, whatever CGAL's): a counting sort by
// the first (smallest) vertex, then each vertex's few tets sorted.
TetMatrix sorted_tets(const std::vector<std::array<int, 4>>& tets, int n) {
  std::vector<int> offsets(std::size_t(n) + 1, 0);
  for (const auto& t : tets) ++offsets[std::size_t(t[0]) + 1];
  for (int i = 0; i < n; ++i) offsets[std::size_t(i) + 1] += offsets[std::size_t(i)];
  std::vector<std::array<int, 4>> order(tets.size());
  {
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (const auto& t : tets) order[std::size_t(fill[std::size_t(t[0])]++)] = t;
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int i = r.begin(); i < r.end(); ++i)
      std::sort(order.begin() + offsets[std::size_t(i)],
                order.begin() + offsets[std::size_t(i) + 1]);
  });
  TetMatrix sorted(Eigen::Index(order.size()), 4);
  for (std::size_t t = 0; t < order.size(); ++t)
    for (int k = 0; k < 4; ++k) sorted(Eigen::Index(t), k) = order[t][std::size_t(k)];
  return sorted;
}

template <class Tr, bool Parallel, class Site>
Triangulation run(const std::vector<std::pair<Site, int>>& sites, const CGAL::Bbox_3& box, int n) {
  std::unique_ptr<Lock> lock;
  std::unique_ptr<Tr> tr;
  if constexpr (Parallel) {
    lock = std::make_unique<Lock>(box, 50);
    tr = std::make_unique<Tr>(lock.get());
  } else {
    tr = std::make_unique<Tr>();
  }
  tr->insert(sites.begin(), sites.end());
  if (tr->dimension() < 3)
    throw Error("all samples are " +
                std::string(tr->dimension() <= 0   ? "coincident"
                            : tr->dimension() == 1 ? "collinear"
                                                   : "coplanar") +
                ": no 3D triangulation exists");

  Triangulation out;
  out.hidden.assign(std::size_t(n), 1);
  for (auto v = tr->finite_vertices_begin(); v != tr->finite_vertices_end(); ++v)
    out.hidden[std::size_t(v->info())] = 0;
  out.hidden_count = int(std::count(out.hidden.begin(), out.hidden.end(), 1));
  out.on_hull.assign(std::size_t(n), 0);
  std::vector<typename Tr::Vertex_handle> hull;
  tr->adjacent_vertices(tr->infinite_vertex(), std::back_inserter(hull));
  for (auto v : hull)
    if (!tr->is_infinite(v)) out.on_hull[std::size_t(v->info())] = 1;

  std::vector<std::array<int, 4>> tets;
  tets.reserve(tr->number_of_finite_cells());
  for (auto c = tr->finite_cells_begin(); c != tr->finite_cells_end(); ++c)
    tets.push_back(canonical_tet(
        {c->vertex(0)->info(), c->vertex(1)->info(), c->vertex(2)->info(), c->vertex(3)->info()}));
  tr.reset();
  out.tets = sorted_tets(tets, n);
  build_adjacency(out, n);
  return out;
}

void build_adjacency(Triangulation& tri, int n) {
  const Eigen::Index m = tri.tets.rows();
  // Incident tets: counting sort by vertex, filled in tet order so each row is ascending.
  tri.incident_offsets.assign(std::size_t(n) + 1, 0);
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) ++tri.incident_offsets[std::size_t(tri.tets(t, k)) + 1];
  for (int i = 0; i < n; ++i)
    tri.incident_offsets[std::size_t(i) + 1] += tri.incident_offsets[std::size_t(i)];
  tri.incident_tets.resize(std::size_t(tri.incident_offsets.back()));
  {
    std::vector<int> fill(tri.incident_offsets.begin(), tri.incident_offsets.end() - 1);
    for (Eigen::Index t = 0; t < m; ++t)
      for (int k = 0; k < 4; ++k)
        tri.incident_tets[std::size_t(fill[std::size_t(tri.tets(t, k))]++)] = int(t);
  }
  // Neighbours: the other vertices of the incident tets, deduplicated with a per-thread stamp
  // (no sort of the ~70 repeats), then sorted. One pass: each block of samples writes its lists
  // to its own buffer, and the buffers are concatenated in block order.
  constexpr int kBlock = 2048;
  const int blocks = (n + kBlock - 1) / kBlock;
  auto lists = std::vector<std::vector<int>>(std::size_t(blocks));
  tri.neighbour_offsets.assign(std::size_t(n) + 1, 0);
  tbb::enumerable_thread_specific<std::vector<int>> stamps;
  tbb::parallel_for(0, blocks, [&](int block) {
    std::vector<int>& stamp = stamps.local();
    if (stamp.empty()) stamp.assign(std::size_t(n), -1);
    std::vector<int>& list = lists[std::size_t(block)];
    const int end = std::min(n, (block + 1) * kBlock);
    for (int i = block * kBlock; i < end; ++i) {
      const std::size_t start = list.size();
      for (int o = tri.incident_offsets[std::size_t(i)];
           o < tri.incident_offsets[std::size_t(i) + 1]; ++o)
        for (int k = 0; k < 4; ++k) {
          const int v = tri.tets(tri.incident_tets[std::size_t(o)], k);
          if (v == i || stamp[std::size_t(v)] == i) continue;
          stamp[std::size_t(v)] = i;
          list.push_back(v);
        }
      std::sort(list.begin() + long(start), list.end());
      tri.neighbour_offsets[std::size_t(i) + 1] = int(list.size() - start);
    }
  });
  for (int i = 0; i < n; ++i)
    tri.neighbour_offsets[std::size_t(i) + 1] += tri.neighbour_offsets[std::size_t(i)];
  tri.neighbour_indices.resize(std::size_t(tri.neighbour_offsets.back()));
  tbb::parallel_for(0, blocks, [&](int block) {
    const std::vector<int>& list = lists[std::size_t(block)];
    std::copy(list.begin(), list.end(),
              tri.neighbour_indices.begin() + tri.neighbour_offsets[std::size_t(block * kBlock)]);
  });
}

}  // namespace

Triangulation triangulate(const PointMatrix& points, const Eigen::VectorXd& values,
                          const TriangulationOptions& options) {
  const int n = int(points.rows());
  if (n < 4) throw Error("need at least 4 samples to triangulate, got " + std::to_string(n));
  CGAL::Bbox_3 box;
  for (int i = 0; i < n; ++i)
    box += CGAL::Bbox_3(points(i, 0), points(i, 1), points(i, 2), points(i, 0), points(i, 1),
                        points(i, 2));
  // The lock grid needs a box with volume; pad flat boxes (coplanar input is rejected later).
  const double pad = 1e-9 + 1e-9 * std::max({box.xmax() - box.xmin(), box.ymax() - box.ymin(),
                                             box.zmax() - box.zmin()});
  box = CGAL::Bbox_3(box.xmin() - pad, box.ymin() - pad, box.zmin() - pad, box.xmax() + pad,
                     box.ymax() + pad, box.zmax() + pad);
  if (options.kind == TriangulationKind::Regular) {
    std::vector<std::pair<Kernel::Weighted_point_3, int>> sites(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      sites[std::size_t(i)] = {
          Kernel::Weighted_point_3(Kernel::Point_3(points(i, 0), points(i, 1), points(i, 2)),
                                   values[i] * values[i]),
          i};
    if (options.parallel) return run<RegularTypes<CGAL::Parallel_tag>::Tr, true>(sites, box, n);
    return run<RegularTypes<CGAL::Sequential_tag>::Tr, false>(sites, box, n);
  }
  std::vector<std::pair<Kernel::Point_3, int>> sites(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    sites[std::size_t(i)] = {Kernel::Point_3(points(i, 0), points(i, 1), points(i, 2)), i};
  if (options.parallel) return run<DelaunayTypes<CGAL::Parallel_tag>::Tr, true>(sites, box, n);
  return run<DelaunayTypes<CGAL::Sequential_tag>::Tr, false>(sites, box, n);
}

}  // namespace sdfcontour
