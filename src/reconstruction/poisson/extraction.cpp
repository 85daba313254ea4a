#include "reconstruction/poisson/extraction.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "extraction/cube_polygons.h"

namespace sdfcontour::poisson {

namespace {

// Finest-depth cells, keyed with a +1 offset so that the ring just outside the domain has keys.
Key cell_key(long i, long j, long k) {
  return pack(i + 1, j + 1, k + 1);
}

// Cells and the polygons in them are found from iso - chi at finest-depth nodes (inside < 0).
class SurfaceCells {
 public:
  SurfaceCells(const Indicator& chi, double iso)
      : chi_(chi), iso_(iso), finest_(chi.tree().level(chi.tree().finest)) {}

  void cell_values(long i, long j, long k, double* value) const {
    for (int c = 0; c < 8; ++c)
      value[c] =
          iso_ - chi_.at_finest_node(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1), iso_ - 1.0);
  }

  // Candidates: finest active cells with a sign change, and subcells of coarser leaves whose
  // corners straddle iso; all distinct, with their cube cases (what their polygons need of their
  // corner values).
  struct Candidates {
    std::vector<Key> cells;
    std::vector<detail::CubeCase> cases;
  };
  Candidates candidates() const {
    Candidates found;
    const Octree& tree = chi_.tree();
    for (int d = tree.min_depth; d < tree.finest; ++d) leaf_candidates(tree.level(d), found);
    finest_candidates(found);
    return found;
  }

  // Closes the candidates: a face with a sign change needs the cell across it. Returns the cells
  // with a sign change, sorted by key, and their cases. Round after round, in parallel: the cells
  // across the sign-changing faces of the last round's new cells, not yet seen. The first round's
  // cases are the candidates' own.
  void close(Candidates first, std::vector<Key>& cells, std::vector<detail::CubeCase>& cases,
             const std::atomic<bool>* cancel) const {
    std::vector<Key> seen;
    Candidates frontier;
    sort_by_key(first, frontier.cells, frontier.cases);
    while (!frontier.cells.empty()) {
      check_cancel(cancel);
      const std::size_t n = frontier.cells.size();
      // Cells seen so far (kept or not) are not visited again.
      std::vector<Key> merged(seen.size() + n);
      std::merge(seen.begin(), seen.end(), frontier.cells.begin(), frontier.cells.end(),
                 merged.begin());
      seen = std::move(merged);
      if (frontier.cases.empty()) {
        frontier.cases.resize(n);
        tbb::parallel_for(std::size_t(0), n, [&](std::size_t c) {
          const auto u = unpack(frontier.cells[c]);
          double value[8];
          cell_values(u[0] - 1, u[1] - 1, u[2] - 1, value);
          frontier.cases[c] = detail::cube_case(value);
        });
      }
      // The next round: per fixed chunk, joined in order (the same whatever the threads).
      constexpr std::size_t kChunk = 4096;
      std::vector<std::vector<Key>> across((n + kChunk - 1) / kChunk);
      tbb::parallel_for(std::size_t(0), across.size(), [&](std::size_t chunk) {
        for (std::size_t c = chunk * kChunk; c < std::min(n, (chunk + 1) * kChunk); ++c) {
          if (!frontier.cases[c].mixed()) continue;
          std::array<Key, 6> neighbours;
          neighbours_across_sign_changes(frontier.cells[c], frontier.cases[c], neighbours);
          for (const Key m : neighbours)
            if (m != kNone && !std::binary_search(seen.begin(), seen.end(), m))
              across[chunk].push_back(m);
        }
      });
      std::vector<Key> next;
      for (const auto& a : across) next.insert(next.end(), a.begin(), a.end());
      sort_unique(next);
      // The cells with a sign change stay: compacted in place, then moved (the first round, the
      // largest) or appended.
      std::size_t kept = 0;
      for (std::size_t c = 0; c < n; ++c)
        if (frontier.cases[c].mixed()) {
          frontier.cells[kept] = frontier.cells[c];
          frontier.cases[kept++] = frontier.cases[c];
        }
      frontier.cells.resize(kept);
      frontier.cases.resize(kept);
      if (cells.empty()) {
        cells = std::move(frontier.cells);
        cases = std::move(frontier.cases);
      } else {
        cells.insert(cells.end(), frontier.cells.begin(), frontier.cells.end());
        cases.insert(cases.end(), frontier.cases.begin(), frontier.cases.end());
      }
      frontier = Candidates{std::move(next), {}};
    }
    // One order whatever the rounds: by key (a single round's cells already are).
    if (std::is_sorted(cells.begin(), cells.end())) return;
    Candidates all{std::move(cells), std::move(cases)};
    sort_by_key(all, cells, cases);
  }

  // The candidates' keys, ascending, and their cases in the same order, moved into keys and
  // cases. Sorted in place (a permutation applied cycle by cycle): a sorted copy would double the
  // extraction's largest arrays.
  static void sort_by_key(Candidates& found, std::vector<Key>& keys,
                          std::vector<detail::CubeCase>& cases) {
    std::vector<std::uint32_t> order(found.cells.size());
    for (std::size_t c = 0; c < order.size(); ++c) order[c] = std::uint32_t(c);
    tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return found.cells[a] < found.cells[b];
    });
    // Position c takes the element at order[c]; each cycle is walked once, and order[c] = c marks
    // a position done.
    for (std::size_t c = 0; c < order.size(); ++c) {
      if (order[c] == c) continue;
      const Key key = found.cells[c];
      const detail::CubeCase cube = found.cases[c];
      std::size_t at = c;
      while (order[at] != c) {
        const std::size_t from = order[at];
        found.cells[at] = found.cells[from];
        found.cases[at] = found.cases[from];
        order[at] = std::uint32_t(at);
        at = from;
      }
      found.cells[at] = key;
      found.cases[at] = cube;
      order[at] = std::uint32_t(at);
    }
    keys = std::move(found.cells);
    cases = std::move(found.cases);
    found = Candidates();
  }

 private:
  static constexpr Key kNone = ~Key(0);

  // The cells across the faces of `cell` with a sign change (kNone elsewhere).
  void neighbours_across_sign_changes(Key cell, detail::CubeCase cube,
                                      std::array<Key, 6>& out) const {
    out.fill(kNone);
    const long R = finest_.res;
    const auto u = unpack(cell);
    const long i = u[0] - 1, j = u[1] - 1, k = u[2] - 1;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        int inside = 0;
        for (int c = 0; c < 8; ++c)
          if ((c >> axis & 1) == side) inside += cube.inside >> c & 1;
        if (inside == 0 || inside == 4) continue;
        long ni = i, nj = j, nk = k;
        (axis == 0 ? ni : axis == 1 ? nj : nk) += side ? 1 : -1;
        if (ni < -1 || nj < -1 || nk < -1 || ni > R || nj > R || nk > R) continue;
        out[std::size_t(2 * axis + side)] = cell_key(ni, nj, nk);
      }
  }

  // The finest subcells with a sign change of leaf c of level L (finest = L's depth + shift), if
  // its corners straddle iso.
  void leaf_subcells(const OctreeLevel& L, int shift, std::size_t c, Candidates& out) const {
    const auto [i, j, k] = unpack(L.cells[c]);
    const long n = 1L << shift;
    int inside = 0;
    for (int q = 0; q < 8; ++q)
      inside += iso_ - chi_.at_finest_node((i + (q & 1)) << shift, (j + (q >> 1 & 1)) << shift,
                                           (k + (q >> 2 & 1)) << shift, iso_ - 1.0) <
                0;
    if (inside == 0 || inside == 8) return;
    for (long a = 0; a < n; ++a)
      for (long b = 0; b < n; ++b)
        for (long e = 0; e < n; ++e) {
          double value[8];
          const long fi = (i << shift) + a, fj = (j << shift) + b, fk = (k << shift) + e;
          cell_values(fi, fj, fk, value);
          const detail::CubeCase cube = detail::cube_case(value);
          if (!cube.mixed()) continue;
          out.cells.push_back(cell_key(fi, fj, fk));
          out.cases.push_back(cube);
        }
  }

  void leaf_candidates(const OctreeLevel& L, Candidates& out) const {
    const int shift = chi_.tree().finest - L.depth;
    // Found per fixed chunk of cells, joined in order: the same list whatever the threads.
    constexpr std::size_t kChunk = 4096;
    std::vector<Candidates> found((L.cells.size() + kChunk - 1) / kChunk);
    tbb::parallel_for(std::size_t(0), found.size(), [&](std::size_t chunk) {
      const std::size_t last = std::min(L.cells.size(), (chunk + 1) * kChunk);
      for (std::size_t c = chunk * kChunk; c < last; ++c)
        if (!L.refined[c]) leaf_subcells(L, shift, c, found[chunk]);
    });
    for (auto& f : found) {
      out.cells.insert(out.cells.end(), f.cells.begin(), f.cells.end());
      out.cases.insert(out.cases.end(), f.cases.begin(), f.cases.end());
    }
  }

  // Finest cells, a line at a time: their corners are finest nodes, found by cursors. A first pass
  // flags the cells with a sign change, a second stores their values in key order.
  void finest_candidates(Candidates& out) const {
    const OctreeLevel& F = finest_;
    const auto& x = chi_.values(F.depth);
    auto for_each_cell = [&](auto&& f) {
      for_each_line(
          F.cell_lines, F.cells, [&](long i, long j, std::size_t first, std::size_t last) {
            LineCursor column[4];
            for (int c = 0; c < 4; ++c)
              column[c] = LineCursor(F.nodes, F.node_lines.line(i + (c & 1), j + (c >> 1)));
            for (std::size_t c = first; c < last; ++c) {
              const long k = long(F.cells[c] & kKeyMask);
              auto values = [&](double* value) {
                for (int q = 0; q < 8; ++q)
                  value[q] = iso_ - x[std::size_t(column[q & 3].find(
                                        pack(i + (q & 1), j + (q >> 1 & 1), k + (q >> 2 & 1))))];
              };
              f(c, values);
            }
          });
    };
    // slot[c]: 0 for a cell with a sign change, -1 otherwise; then its rank among them.
    std::vector<int> slot(F.cells.size());
    for_each_cell([&](std::size_t c, auto&& values) {
      double value[8];
      values(value);
      slot[c] = detail::cube_case(value).mixed() ? 0 : -1;
    });
    const std::size_t before = out.cells.size();
    for (std::size_t c = 0; c < F.cells.size(); ++c)
      if (slot[c] >= 0) {
        const auto [i, j, k] = unpack(F.cells[c]);
        slot[c] = int(out.cells.size() - before);
        out.cells.push_back(cell_key(i, j, k));
      }
    out.cases.resize(out.cells.size());
    for_each_cell([&](std::size_t c, auto&& values) {
      if (slot[c] < 0) return;
      double value[8];
      values(value);
      out.cases[before + std::size_t(slot[c])] = detail::cube_case(value);
    });
  }

  const Indicator& chi_;
  double iso_;
  const OctreeLevel& finest_;
};

// The global key of local edge e of the cell with (offset) key `cell`: its low node's key times 3
// plus its axis.
Key global_edge(Key cell, int e) {
  const auto u = unpack(cell);
  const int low = detail::cube_tables().edge_low_corner[e];
  return pack(u[0] + (low & 1), u[1] + (low >> 1 & 1), u[2] + (low >> 2 & 1)) * 3 + Key(e / 4);
}

}  // namespace

namespace {

// Where on [0, 1] the quadratic through (0, v0), (1/2, vm), (1, v1) crosses 0, v0 and v1 of
// opposite signs (so it crosses once); the linear interpolation if it is nearly linear.
double quadratic_root(double v0, double vm, double v1) {
  const double linear = v0 / (v0 - v1);
  // q(t) = a t^2 + b t + v0.
  const double a = 2 * v0 - 4 * vm + 2 * v1, b = -3 * v0 + 4 * vm - v1;
  if (std::abs(a) <= 1e-12 * (std::abs(v0) + std::abs(v1))) return linear;
  const double disc = b * b - 4 * a * v0;
  if (disc < 0) return linear;
  const double s = std::sqrt(disc);
  for (const double t : {(-b + s) / (2 * a), (-b - s) / (2 * a)})
    if (t >= 0 && t <= 1) return t;
  return linear;
}

}  // namespace

Mesh extract_iso_surface(const Indicator& chi, double iso, const UnitPoints& frame,
                         const std::atomic<bool>* cancel,
                         const std::function<double(const Eigen::Vector3d&)>& along_edges) {
  const SurfaceCells surface(chi, iso);
  std::vector<Key> cells;
  std::vector<detail::CubeCase> cases;
  surface.close(surface.candidates(), cells, cases, cancel);
  // Polygons per cell, found twice (the cube's case is cheap to redo; storing them took ~150
  // bytes per surface cell, the extraction's largest array): first for the global keys of their
  // edges, where vertices are deduplicated, then for the triangles. Fixed chunks of cells, joined
  // in order: the mesh does not depend on the threads.
  constexpr std::size_t kChunk = 8192;
  const std::size_t chunks = (cells.size() + kChunk - 1) / kChunk;
  auto for_each_polygon = [&](std::size_t chunk, auto&& f) {
    const std::size_t last = std::min(cells.size(), (chunk + 1) * kChunk);
    for (std::size_t c = chunk * kChunk; c < last; ++c)
      detail::cube_polygons(cases[c], [&](const int* edges, int size) { f(c, edges, size); });
  };
  std::vector<std::vector<Key>> chunk_edges(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    for_each_polygon(chunk, [&](std::size_t c, const int* edges, int size) {
      for (int v = 0; v < size; ++v) chunk_edges[chunk].push_back(global_edge(cells[c], edges[v]));
    });
  });
  std::vector<Key> edge_keys;
  std::size_t emitted = 0;
  for (const auto& e : chunk_edges) emitted += e.size();
  edge_keys.reserve(emitted);  // no doubling of the largest list on the way
  for (auto& e : chunk_edges) {
    edge_keys.insert(edge_keys.end(), e.begin(), e.end());
    std::vector<Key>().swap(e);
  }
  sort_unique(edge_keys);
  edge_keys.shrink_to_fit();  // it held every cell's copy of each edge: ~4x the unique ones
  // A vertex's id is its edge key's rank, found by binary search (a hash index over the keys took
  // 16 bytes a slot at half load: more than the vertices themselves).
  auto vertex_id = [&](Key edge) {
    return int(std::lower_bound(edge_keys.begin(), edge_keys.end(), edge) - edge_keys.begin());
  };
  const long R = chi.tree().level(chi.tree().finest).res;
  Mesh mesh;
  mesh.vertices.resize(Eigen::Index(edge_keys.size()), 3);
  tbb::parallel_for(std::size_t(0), edge_keys.size(), [&](std::size_t e) {
    const Key node_key = edge_keys[e] / 3;
    const int axis = int(edge_keys[e] % 3);
    const auto u = unpack(node_key);
    const long i = u[0] - 1, j = u[1] - 1, k = u[2] - 1;
    const double v0 = iso - chi.at_finest_node(i, j, k, iso - 1.0);
    const double v1 =
        iso - chi.at_finest_node(i + (axis == 0), j + (axis == 1), k + (axis == 2), iso - 1.0);
    const Eigen::Vector3d p0(static_cast<double>(i), static_cast<double>(j),
                             static_cast<double>(k));
    Eigen::Vector3d p1 = p0;
    p1[axis] += 1;
    const double t = along_edges
                         ? quadratic_root(v0, iso - along_edges((0.5 * (p0 + p1)) / double(R)), v1)
                         : v0 / (v0 - v1);
    const Eigen::Vector3d unit = (p0 + t * (p1 - p0)) / double(R);
    mesh.vertices.row(Eigen::Index(e)) = frame.from_unit(unit).transpose();
  });
  std::vector<detail::PolygonOutput> out(chunks);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    for_each_polygon(chunk, [&](std::size_t c, const int* edges, int count) {
      int ids[12];
      Eigen::Vector3d position[12];
      for (int v = 0; v < count; ++v) {
        ids[v] = vertex_id(global_edge(cells[c], edges[v]));
        position[v] = mesh.vertices.row(ids[v]).transpose();
      }
      detail::triangulate_polygon(ids, edges, position, count, out[chunk]);
    });
  });
  // The surface cells and edges are done with: freed before the triangles are joined.
  std::vector<Key>().swap(cells);
  std::vector<detail::CubeCase>().swap(cases);
  std::vector<Key>().swap(edge_keys);
  detail::polygons_to_mesh(out, mesh);
  return mesh;
}

}  // namespace sdfcontour::poisson
