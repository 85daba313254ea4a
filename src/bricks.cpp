#include "sdfcontour/bricks.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <string>

#include "brick_geometry.h"
#include "sdfcontour/triangulation.h"

namespace sdfcontour {

namespace {

using Eigen::Vector3d;
using Box = BrickBox;

// Samples bucketed by brick, each bucket in ascending sample order.
struct BrickGrid {
  Vector3d origin;
  double side = 0;
  std::array<int, 3> dims{1, 1, 1};
  std::vector<long> offsets;  // dims product + 1
  std::vector<int> members;

  int count() const { return dims[0] * dims[1] * dims[2]; }
  int id(int i, int j, int k) const { return (i * dims[1] + j) * dims[2] + k; }
  std::array<int, 3> cell_of(const Vector3d& p) const {
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a)
      c[std::size_t(a)] = std::clamp(int(std::floor((p[a] - origin[a]) / side)), 0, dims[a] - 1);
    return c;
  }
  Box box(int b) const {
    const int k = b % dims[2], j = b / dims[2] % dims[1], i = b / (dims[1] * dims[2]);
    const Vector3d lo = origin + side * Vector3d(i, j, k);
    return {lo, lo + Vector3d::Constant(side)};
  }
};

BrickGrid bucket(const PointMatrix& points, double side) {
  BrickGrid g;
  g.origin = points.colwise().minCoeff().transpose();
  const Vector3d extent = points.colwise().maxCoeff().transpose() - g.origin;
  g.side = side;
  for (int a = 0; a < 3; ++a)
    g.dims[std::size_t(a)] = std::max(1, int(std::ceil(extent[a] / side + 1e-9)));
  const Eigen::Index n = points.rows();
  std::vector<int> brick_of(static_cast<std::size_t>(n));
  g.offsets.assign(std::size_t(g.count()) + 1, 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto c = g.cell_of(points.row(i).transpose());
    brick_of[std::size_t(i)] = g.id(c[0], c[1], c[2]);
    ++g.offsets[std::size_t(brick_of[std::size_t(i)]) + 1];
  }
  for (int b = 0; b < g.count(); ++b) g.offsets[std::size_t(b) + 1] += g.offsets[std::size_t(b)];
  g.members.resize(std::size_t(n));
  std::vector<long> fill(g.offsets.begin(), g.offsets.end() - 1);
  for (Eigen::Index i = 0; i < n; ++i)
    g.members[std::size_t(fill[std::size_t(brick_of[std::size_t(i)])]++)] = int(i);
  return g;
}

// The samples inside `box`, ascending.
std::vector<int> gather(const BrickGrid& g, const PointMatrix& points, const Box& box) {
  const auto lo = g.cell_of(box.min), hi = g.cell_of(box.max);
  std::vector<int> out;
  for (int i = lo[0]; i <= hi[0]; ++i)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int k = lo[2]; k <= hi[2]; ++k) {
        const int b = g.id(i, j, k);
        for (long m = g.offsets[std::size_t(b)]; m < g.offsets[std::size_t(b) + 1]; ++m) {
          const int s = g.members[std::size_t(m)];
          if (box.contains(Vector3d(points.row(s).transpose()))) out.push_back(s);
        }
      }
  std::sort(out.begin(), out.end());
  return out;
}

// Adds `from`'s outcome counts to `to`'s.
void add_counts(ContactPoints& to, const ContactPoints& from) {
  to.hidden += from.hidden;
  to.zero_gradient += from.zero_gradient;
  to.discarded += from.discarded;
  to.rescued += from.rescued;
}

struct BrickOutput {
  ContactPoints kept;  // samples named by global index, in the order solved
  long triangulated = 0, largest = 0;
  int retries = 0;
};

class BrickRunner {
 public:
  BrickRunner(const Samples& s, double h, const GradientOptions& g, const ContactPointOptions& c,
              const BrickOptions& o, const std::vector<char>* only)
      : s_(s),
        h_(h),
        gradient_(g),
        contact_(c),
        options_(o),
        only_(only),
        grid_(bucket(s.points, o.size * h)) {
    max_weight_ = s.values.array().square().maxCoeff();
    all_ = {s.points.colwise().minCoeff().transpose(), s.points.colwise().maxCoeff().transpose()};
    margin_ = 1e-9 * (all_.max - all_.min).maxCoeff();
    std::vector<std::vector<int>> buckets(std::size_t(grid_.count()));
    for (int b = 0; b < grid_.count(); ++b)
      buckets[std::size_t(b)].assign(grid_.members.begin() + grid_.offsets[std::size_t(b)],
                                     grid_.members.begin() + grid_.offsets[std::size_t(b) + 1]);
    hull_ = convex_hull_vertices(s.points, buckets);
  }
  const BrickGrid& grid() const { return grid_; }

  BrickOutput run(int brick) const {
    check_cancel(options_.cancel);
    BrickOutput out;
    std::vector<int> targets;
    const BrickGrid& g = grid_;
    for (long m = g.offsets[std::size_t(brick)]; m < g.offsets[std::size_t(brick) + 1]; ++m) {
      const int s = g.members[std::size_t(m)];
      if (!only_ || (*only_)[std::size_t(s)]) targets.push_back(s);
    }
    const Box own = grid_.box(brick);
    const Vector3d halo = Vector3d::Constant(options_.halo * h_);
    solve({own.min - halo, own.max + halo}, targets, out);
    return out;
  }

 private:
  // Contact points of `targets` (ascending sample indices inside `box`) from the triangulation
  // of the samples in `box`. Targets whose stars it cannot certify are solved again in a box
  // grown to hold the orthospheres that failed (or, if that is no growth, twice as wide).
  void solve(const Box& box, const std::vector<int>& targets, BrickOutput& out) const {
    if (targets.empty()) return;
    const bool everything = box.contains(all_);
    const std::vector<int> local = gather(grid_, s_.points, box);
    Samples ls;
    Triangulation tri;
    Box need = box;
    std::vector<int> failed;
    std::vector<char> keep(local.size(), 0);
    if (triangulate_local(local, everything, ls, tri)) {
      check_cancel(options_.cancel);
      out.triangulated += long(local.size());
      out.largest = std::max(out.largest, long(local.size()));
      std::vector<signed char> tet_inside(std::size_t(tri.tets.rows()), -1);
      for (std::size_t r = 0, t = 0; r < local.size() && t < targets.size(); ++r) {
        if (local[r] != targets[t]) continue;
        ++t;
        if (everything || tri.hidden[r] || certified(ls, tri, r, box, need, tet_inside))
          keep[r] = 1;
        else
          failed.push_back(local[r]);
      }
      const PointMatrix g = vertex_gradients(ls.points, ls.values, tri, gradient_, &keep);
      collect(gradient_contact_points(ls.points, ls.values, g, tri, contact_, &keep), local, out);
    } else {
      failed = targets;
    }
    if (failed.empty()) return;
    ++out.retries;
    const Vector3d grow = (box.max - box.min) / 2;
    if ((need.min.array() >= box.min.array()).all() && (need.max.array() <= box.max.array()).all())
      need = {box.min - grow, box.max + grow};
    solve(need, failed, out);
  }

  // The local samples' triangulation; false if there is none yet (too few or flat samples).
  bool triangulate_local(const std::vector<int>& local, bool everything, Samples& ls,
                         Triangulation& tri) const {
    if (local.size() < 4 && !everything) return false;
    ls.points.resize(Eigen::Index(local.size()), 3);
    ls.values.resize(Eigen::Index(local.size()));
    for (std::size_t r = 0; r < local.size(); ++r) {
      ls.points.row(Eigen::Index(r)) = s_.points.row(local[r]);
      ls.values[Eigen::Index(r)] = s_.values[local[r]];
    }
    TriangulationOptions topt;
    topt.parallel = false;  // bricks are the parallel unit
    try {
      tri = triangulate(ls.points, ls.values, topt);
    } catch (const Error&) {
      if (everything) throw;
      return false;
    }
    return true;
  }

  // Local row r's star is the global one: every orthosphere inside `box` and, on the local
  // hull, every hull facet a global one. Failing orthospheres grow `need`. `tet_inside` caches
  // each tet's verdict (-1: not yet), as a tet is in up to four stars.
  bool certified(const Samples& ls, const Triangulation& tri, std::size_t r, const Box& box,
                 Box& need, std::vector<signed char>& tet_inside) const {
    if (tri.on_hull[r] &&
        !hull_facets_global(ls, tri, int(r), hull_, max_weight_, margin_, box, need))
      return false;
    bool ok = true;
    for (int o = tri.incident_offsets[r]; o < tri.incident_offsets[r + 1]; ++o) {
      const int t = tri.incident_tets[std::size_t(o)];
      signed char& inside = tet_inside[std::size_t(t)];
      if (inside < 0)
        inside = orthosphere_inside(ls.points, ls.values, tri.tets.row(t).data(), box, max_weight_,
                                    margin_, need);
      ok &= inside == 1;
    }
    return ok;
  }

  // Appends the kept points, in global indices, and their counts.
  static void collect(const ContactPoints& cp, const std::vector<int>& local, BrickOutput& out) {
    ContactPoints& to = out.kept;
    const Eigen::Index at = to.points.rows(), k = cp.points.rows();
    to.points.conservativeResize(at + k, 3);
    to.normals.conservativeResize(at + k, 3);
    to.points.bottomRows(k) = cp.points;
    to.normals.bottomRows(k) = cp.normals;
    for (int s : cp.samples) to.samples.push_back(local[std::size_t(s)]);
    add_counts(to, cp);
  }

  const Samples& s_;
  double h_;
  const GradientOptions& gradient_;
  const ContactPointOptions& contact_;
  const BrickOptions& options_;
  const std::vector<char>* only_;
  BrickGrid grid_;
  double max_weight_ = 0, margin_ = 0;
  Box all_;
  std::vector<Vector3d> hull_;  // the vertices of every sample's convex hull
};

}  // namespace

int auto_brick_size(const PointMatrix& points, double spacing, int threads) {
  if (!(spacing > 0) || !std::isfinite(spacing)) throw Error("the spacing must be positive");
  for (int side : {256, 192, 160, 128, 96}) {
    const BrickGrid grid = bucket(points, side * spacing);
    int active = 0;
    long largest = 0;
    for (int b = 0; b < grid.count(); ++b) {
      const long own = grid.offsets[std::size_t(b) + 1] - grid.offsets[std::size_t(b)];
      active += own > 0;
      largest = std::max(largest, own);
    }
    if (active >= 4 * std::max(threads, 1) && largest <= kMaxBrickSamples) return side;
  }
  return 64;
}

ContactPoints brick_contact_points(const Samples& samples, double spacing,
                                   const GradientOptions& gradient,
                                   const ContactPointOptions& contact, const BrickOptions& options,
                                   BrickStats* stats, const std::function<void(int, int)>& progress,
                                   const std::vector<char>* only) {
  if (options.size < 1 && options.size != BrickOptions::kAutoSize)
    throw Error("the brick size must be at least 1 spacing, got " + std::to_string(options.size));
  if (!(options.halo > 0) || !std::isfinite(options.halo))
    throw Error("the brick halo must be a positive number of spacings (resolve 0 first)");
  if (!(spacing > 0) || !std::isfinite(spacing)) throw Error("the spacing must be positive");
  BrickOptions resolved = options;
  if (resolved.size == BrickOptions::kAutoSize)
    resolved.size =
        auto_brick_size(samples.points, spacing, tbb::this_task_arena::max_concurrency());
  const BrickRunner runner(samples, spacing, gradient, contact, resolved, only);
  const BrickGrid& grid = runner.grid();
  std::vector<int> active;
  for (int b = 0; b < grid.count(); ++b)
    if (grid.offsets[std::size_t(b) + 1] > grid.offsets[std::size_t(b)]) active.push_back(b);
  // Largest bricks first, each worker taking the next one: the last to start is a small one, so
  // no thread idles long at the end (bricks are few, about four per thread; a parallel_for would
  // split the range in halves and could give one thread all the large ones). The merge below
  // restores the sample order.
  auto own = [&](int b) { return grid.offsets[std::size_t(b) + 1] - grid.offsets[std::size_t(b)]; };
  std::stable_sort(active.begin(), active.end(), [&](int a, int b) { return own(a) > own(b); });
  std::vector<BrickOutput> outputs(active.size());
  std::mutex progress_mutex;
  int done = 0;
  std::atomic<std::size_t> next{0};
  const int workers =
      std::max(1, std::min(tbb::this_task_arena::max_concurrency(), int(active.size())));
  tbb::parallel_for(0, workers, 1, [&](int) {
    for (std::size_t a; (a = next++) < active.size();) {
      outputs[a] = runner.run(active[a]);
      if (progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        progress(++done, int(active.size()));
      }
    }
  });

  // Merge in ascending sample order: the global function's order.
  ContactPoints result;
  std::vector<std::pair<int, std::pair<std::size_t, Eigen::Index>>> order;
  BrickStats st;
  st.bricks = int(active.size());
  st.size = resolved.size;
  for (std::size_t a = 0; a < outputs.size(); ++a) {
    const BrickOutput& o = outputs[a];
    for (std::size_t r = 0; r < o.kept.samples.size(); ++r)
      order.push_back({o.kept.samples[r], {a, Eigen::Index(r)}});
    add_counts(result, o.kept);
    st.retries += o.retries;
    st.triangulated += o.triangulated;
    st.largest_brick = std::max(st.largest_brick, o.largest);
  }
  std::sort(order.begin(), order.end());
  result.points.resize(Eigen::Index(order.size()), 3);
  result.normals.resize(Eigen::Index(order.size()), 3);
  result.samples.resize(order.size());
  for (std::size_t r = 0; r < order.size(); ++r) {
    const auto& [a, row] = order[r].second;
    result.samples[r] = order[r].first;
    result.points.row(Eigen::Index(r)) = outputs[a].kept.points.row(row);
    result.normals.row(Eigen::Index(r)) = outputs[a].kept.normals.row(row);
  }
  if (stats) *stats = st;
  return result;
}

}  // namespace sdfcontour
