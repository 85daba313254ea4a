#include "sdfcontour/metrics/self_intersections.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>

#include "input/parallel_select.h"
#include "metrics/clear_turns.h"
#include "pipeline/float_bounds.h"
#include "pipeline/uninitialised_allocator.h"
#include "pipeline/work_counter.h"
#include "reconstruction/carving_internal.h"
#include "reconstruction/triangle_cells.h"

namespace sdfcontour {

namespace {

using detail::CellGrid;
using detail::TriangleCells;

// A triangle's axis-aligned box, in floats rounded outwards: half the memory of doubles (two
// arrays of boxes were 0.65 GB of a 512^3 brick's untangling), and a box that still holds the
// triangle, as the exact test after it needs. Its arrays are left unwritten when made and filled
// in parallel: value-initialised, the page faults were a quarter of a 256^3 mesh's search set-up.
struct Box {
  Eigen::Vector3f lo, hi;
  static Box empty() {
    return {Eigen::Vector3f::Constant(INFINITY), Eigen::Vector3f::Constant(-INFINITY)};
  }
  void extend(const Eigen::Vector3d& x) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], detail::float_below(x[a]));
      hi[a] = std::max(hi[a], detail::float_above(x[a]));
    }
  }
  void extend(const Box& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  bool meets(const Box& b) const {
    return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all();
  }
  Eigen::Vector3d low() const { return lo.cast<double>(); }
  Eigen::Vector3d high() const { return hi.cast<double>(); }
};

}  // namespace

template <>
struct detail::LeftUnwritten<Box> : std::true_type {};  // (Eigen's vectors write nothing)

namespace {

using detail::Unwritten;

// The triangles listed per cube that their boxes (`boxes`) meet. The cubes are about twice a
// typical triangle's extent, so most triangles sit in one to eight of them.
TriangleCells bucketed_by_cube(const Unwritten<Box>& boxes) {
  const std::size_t count = boxes.size();
  const Box all = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, count), Box::empty(),
      [&](const tbb::blocked_range<std::size_t>& r, Box b) {
        for (std::size_t t = r.begin(); t < r.end(); ++t) b.extend(boxes[t]);
        return b;
      },
      [](Box a, const Box& b) {
        a.extend(b);
        return a;
      });
  if (count == 0) return TriangleCells(CellGrid(), {});
  std::vector<double> extents(count);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t t) {
    extents[t] = (boxes[t].high() - boxes[t].low()).maxCoeff();
  });
  const double middle = detail::kth_smallest(extents, count / 2);
  const Eigen::Vector3d extent = all.high() - all.low();
  double cell = std::max(2 * middle, 1e-12 * std::max(extent.maxCoeff(), 1e-300));
  // The triangles may not sit in too many cubes in all (a few huge ones would): coarser cubes
  // only cost more tests. (Sums of whole numbers: the same in any order.)
  auto entries = [&] {
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double sum) {
          for (std::size_t t = r.begin(); t < r.end(); ++t)
            sum += (((boxes[t].high() - boxes[t].low()).array() / cell).floor() + 2).prod();
          return sum;
        },
        std::plus<double>());
  };
  while (entries() > 64.0 * double(count) + 1e6) cell *= 2;
  // (Any number of columns: far-apart parts keep only their occupied ones.)
  const CellGrid grid = CellGrid::over(all.low(), all.high(), cell, INFINITY);
  std::vector<TriangleCells::Range> ranges(count);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t t) {
    ranges[t] = {grid.cube_of(boxes[t].low()), grid.cube_of(boxes[t].high())};
  });
  return TriangleCells(grid, ranges);
}

std::array<Eigen::Vector3d, 3> corners(const Mesh& mesh, int t) {
  std::array<Eigen::Vector3d, 3> c;
  for (int k = 0; k < 3; ++k)
    c[std::size_t(k)] = mesh.vertices.row(mesh.triangles(t, k)).transpose();
  return c;
}

std::array<int, 3> ids(const Mesh& mesh, int t) {
  return {mesh.triangles(t, 0), mesh.triangles(t, 1), mesh.triangles(t, 2)};
}

// Whether triangles s and t meet other than in the vertices and edge they share.
bool cross(const Mesh& mesh, int s, int t) {
  return detail::triangles_cross(corners(mesh, s), ids(mesh, s), corners(mesh, t), ids(mesh, t));
}

bool degenerate(const Mesh& mesh, int t) {
  return detail::collinear_corners(corners(mesh, t));
}

// One flag per triangle: whether any of its vertices is flagged in `vertices`.
std::vector<char> triangles_with(const Mesh& mesh, const std::vector<char>& vertices) {
  std::vector<char> out(std::size_t(mesh.triangles.rows()), 0);
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) out[std::size_t(t)] |= vertices[std::size_t(mesh.triangles(t, c))];
  return out;
}

// Whether vertex v's triangles (`around`'s list), seen along their summed normal, form one closed
// fan round it (each triangle's edge after v is the next one's edge before it), each turning the
// same way by a clear angle, and together once round. Their projections then lie in sectors that
// meet only along the shared edges' rays, so no two of them meet but in the vertex and the edges
// they share: pairs that share the vertex need no test.
bool embedded_star(const Mesh& mesh, const detail::VertexTriangles& around, int v) {
  constexpr int kMostAround = 32;
  const int from = around.offsets[std::size_t(v)], to = around.offsets[std::size_t(v) + 1];
  const int count = to - from;
  if (count < 3 || count > kMostAround) return false;
  int after[kMostAround], before[kMostAround];  // per triangle: its corners after v, in order
  for (int i = 0; i < count; ++i) {
    const int t = around.triangles[std::size_t(from + i)];
    int c = 0;
    while (c < 3 && mesh.triangles(t, c) != v) ++c;
    if (c == 3) return false;
    after[i] = mesh.triangles(t, (c + 1) % 3);
    before[i] = mesh.triangles(t, (c + 2) % 3);
  }
  // One cycle through all of them: from the first, each next one starts where the last ended.
  for (int i = 0, at = 0; i < count; ++i) {
    int next = -1;
    for (int j = 0; j < count; ++j)
      if (after[j] == before[at]) {
        if (next >= 0) return false;  // two fans, or a fold
        next = j;
      }
    if (next < 0 || (next == 0) != (i == count - 1)) return false;
    at = next;
  }
  const Eigen::Vector3d o = mesh.vertices.row(v).transpose();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < count; ++i)
    sum += (mesh.vertices.row(after[i]).transpose() - o)
               .cross(mesh.vertices.row(before[i]).transpose() - o);
  const double length = sum.norm();
  if (!(length > 0) || !std::isfinite(length)) return false;
  const Eigen::Vector3d n = sum / length;
  auto projected = [&](int w) {
    const Eigen::Vector3d a = mesh.vertices.row(w).transpose() - o;
    return (a - a.dot(n) * n).eval();
  };
  auto clearly = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
    return detail::clearly_turns(n, x, y);
  };
  // Each sector turns the same way by a clear angle (under a half turn), so the fan turns once
  // round iff a ray from the vertex lies in one sector alone: the first edge's ray starts the
  // first sector and ends the last; every other sector must clearly leave it out.
  const Eigen::Vector3d ray = projected(after[0]);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d a = projected(after[i]), b = projected(before[i]);
    if (!clearly(a, b)) return false;
    const bool last = before[i] == after[0];
    if (i > 0 && !last && !(clearly(ray, a) || clearly(b, ray))) return false;
  }
  return true;
}

// The triangles' boxes and cube buckets, built once for rounds of tests while vertices move back
// to `before`: each triangle is bucketed by the box of its current and earlier positions, which
// holds every box it can have in between.
class CrossingSearch {
 public:
  CrossingSearch(const Mesh& mesh, const PointMatrix* before)
      : bucketed_(bucketed_boxes(mesh, before)),
        current_(bucketed_.size()),
        flat_(bucketed_.size()),
        cubes_(bucketed_by_cube(bucketed_)),
        around_(mesh),
        embedded_(std::size_t(mesh.vertices.rows())) {
    tbb::parallel_for(Eigen::Index(0), mesh.triangles.rows(),
                      [&](Eigen::Index t) { refresh(mesh, int(t)); });
    tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
      embedded_[std::size_t(v)] = embedded_star(mesh, around_, int(v));
    });
  }

  // Triangle t's box and flatness from the mesh's current positions; with `stars`, its vertices'
  // stars too (after its vertices moved: call it for every triangle around them).
  void refresh(const Mesh& mesh, int t, bool stars = false) {
    Box box = Box::empty();
    for (int c = 0; c < 3; ++c) box.extend(mesh.vertices.row(mesh.triangles(t, c)).transpose());
    current_[std::size_t(t)] = box;
    flat_[std::size_t(t)] = degenerate(mesh, t);
    if (stars)
      for (int c = 0; c < 3; ++c) {
        const int v = mesh.triangles(t, c);
        embedded_[std::size_t(v)] = embedded_star(mesh, around_, v);
      }
  }

  // The crossing pairs with a watched triangle (all if `watch` is null), ascending.
  // `counter` (optional) counts the watched triangles tested.
  std::vector<std::pair<int, int>> find(const Mesh& mesh, const std::vector<char>* watch,
                                        detail::WorkCounter* counter = nullptr) const {
    auto watched = [&](int t) { return !watch || (*watch)[std::size_t(t)]; };
    tbb::enumerable_thread_specific<std::vector<std::pair<int, int>>> found;
    // Where a quarter or more of the triangles are watched (all, after a projection), the sweep
    // over the cubes' pairs finds the same pairs without a search for each triangle's cubes.
    const auto count = std::size_t(mesh.triangles.rows());
    const auto watched_count =
        watch ? std::size_t(std::count_if(watch->begin(), watch->end(), [](char w) { return w; }))
              : count;
    if (4 * watched_count >= count) {
      cubes_.for_each_pair([&](int t, int u) {
        if (current_[std::size_t(t)].meets(current_[std::size_t(u)]) &&
            (watched(t) || watched(u)) && !flat_[std::size_t(t)] && !flat_[std::size_t(u)] &&
            !share_embedded(mesh, t, u) && cross(mesh, t, u))
          found.local().emplace_back(t, u);
      });
      if (counter) counter->add(long(count));
      return sorted_pairs(found);
    }
    tbb::parallel_for(Eigen::Index(0), mesh.triangles.rows(), [&](Eigen::Index ti) {
      const int t = int(ti);
      if (!watched(t)) return;
      if (counter) counter->add();
      if (flat_[std::size_t(t)]) return;
      const Box& box = current_[std::size_t(t)];
      cubes_.for_each_in(cubes_.range(box.low(), box.high()), [&](int u) {
        // Each pair once: from its lower triangle when both are watched.
        if (!box.meets(current_[std::size_t(u)]) || u == t || (watched(u) && u < t) ||
            flat_[std::size_t(u)] || share_embedded(mesh, t, u))
          return;
        if (cross(mesh, t, u)) found.local().emplace_back(std::min(t, u), std::max(t, u));
      });
    });
    return sorted_pairs(found);
  }

 private:
  // Whether triangles t and u share a vertex whose star is embedded (they meet only in what they
  // share).
  bool share_embedded(const Mesh& mesh, int t, int u) const {
    for (int a = 0; a < 3; ++a) {
      const int v = mesh.triangles(t, a);
      if (embedded_[std::size_t(v)] &&
          (v == mesh.triangles(u, 0) || v == mesh.triangles(u, 1) || v == mesh.triangles(u, 2)))
        return true;
    }
    return false;
  }

  static std::vector<std::pair<int, int>> sorted_pairs(
      const tbb::enumerable_thread_specific<std::vector<std::pair<int, int>>>& found) {
    std::vector<std::pair<int, int>> pairs;
    for (const auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
    std::sort(pairs.begin(), pairs.end());
    return pairs;
  }

  static Unwritten<Box> bucketed_boxes(const Mesh& mesh, const PointMatrix* before) {
    Unwritten<Box> boxes(std::size_t(mesh.triangles.rows()));
    tbb::parallel_for(Eigen::Index(0), mesh.triangles.rows(), [&](Eigen::Index t) {
      Box box = Box::empty();
      for (int c = 0; c < 3; ++c) {
        const int v = mesh.triangles(t, c);
        box.extend(mesh.vertices.row(v).transpose());
        if (before) box.extend(before->row(v).transpose());
      }
      boxes[std::size_t(t)] = box;
    });
    return boxes;
  }

  Unwritten<Box> bucketed_, current_;
  Unwritten<char> flat_;
  TriangleCells cubes_;
  detail::VertexTriangles around_;
  std::vector<char> embedded_;  // per vertex: embedded_star
};

}  // namespace

std::vector<std::pair<int, int>> self_intersecting_triangles(const Mesh& mesh,
                                                             const std::vector<char>* watch) {
  const Eigen::Index m = mesh.triangles.rows();
  if (watch && watch->size() != std::size_t(m))
    throw Error("self-intersections: " + std::to_string(watch->size()) + " flags for " +
                std::to_string(m) + " triangles");
  if (m < 2) return {};
  return CrossingSearch(mesh, nullptr).find(mesh, watch);
}

UntangleStats revert_self_intersections(Mesh& mesh, const PointMatrix& before, int max_rounds,
                                        std::vector<char>* reverted,
                                        const std::function<void(long, long)>& progress) {
  if (before.rows() != mesh.vertices.rows())
    throw Error("self-intersections: " + std::to_string(before.rows()) + " earlier positions for " +
                std::to_string(mesh.vertices.rows()) + " vertices");
  UntangleStats stats;
  const Eigen::Index n = mesh.vertices.rows(), m = mesh.triangles.rows();
  auto moved = [&](int v) { return mesh.vertices.row(v) != before.row(v); };
  if (reverted) reverted->assign(std::size_t(n), 0);
  if (m < 2) return stats;
  // First the triangles around any moved vertex, then those around the vertices moved back.
  std::vector<char> moved_vertices(std::size_t(n), 0);
  for (Eigen::Index v = 0; v < n; ++v) moved_vertices[std::size_t(v)] = moved(int(v));
  std::vector<char> watch = triangles_with(mesh, moved_vertices);
  // Nothing moved: nothing to undo, and no search over the whole mesh to build.
  if (std::none_of(watch.begin(), watch.end(), [](char w) { return w != 0; })) return stats;
  CrossingSearch search(mesh, &before);
  detail::WorkCounter tested(
      progress, long(watch.size() - std::size_t(std::count(watch.begin(), watch.end(), char(0)))));
  for (; max_rounds <= 0 || stats.rounds < max_rounds;) {
    const auto pairs = search.find(mesh, &watch, stats.rounds == 0 ? &tested : nullptr);
    if (stats.rounds++ == 0) stats.intersections_found = long(pairs.size());
    std::vector<char> back(std::size_t(n), 0);
    bool any = false;
    for (const auto& [s, t] : pairs)
      for (int tri : {s, t})
        for (int c = 0; c < 3; ++c) {
          const int v = mesh.triangles(tri, c);
          if (moved(v)) back[std::size_t(v)] = 1, any = true;
        }
    if (!any) {
      stats.intersections_left = long(pairs.size());
      return stats;
    }
    for (Eigen::Index v = 0; v < n; ++v)
      if (back[std::size_t(v)]) {
        mesh.vertices.row(v) = before.row(v);
        ++stats.vertices_reverted;
        if (reverted) (*reverted)[std::size_t(v)] = 1;
      }
    watch = triangles_with(mesh, back);
    for (Eigen::Index t = 0; t < m; ++t)
      if (watch[std::size_t(t)]) search.refresh(mesh, int(t), true);
  }
  return stats;  // after max_rounds: the pairs left are not counted
}

}  // namespace sdfcontour
