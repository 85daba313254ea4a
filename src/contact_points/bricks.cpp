#include "sdfcontour/contact_points/bricks.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <set>
#include <string>

#include "contact_points/brick_geometry.h"
#include "contact_points/brick_shell.h"
#include "sdfcontour/contact_points/triangulation.h"

namespace sdfcontour {

namespace {

using Eigen::Vector3d;
using Box = BrickBox;

using Cell = std::array<long, 3>;

// Samples bucketed by brick, each bucket in ascending sample order. Only bricks that hold samples
// exist (sorted by cell, so numbered as a dense grid would order them): objects far apart cost
// nothing for the empty space between them.
struct BrickGrid {
  Vector3d origin;
  double side = 0;
  std::vector<Cell> cells;    // the occupied bricks' cells, ascending
  std::vector<long> offsets;  // cells.size() + 1
  std::vector<int> members;

  int count() const { return int(cells.size()); }
  Cell cell_of(const Vector3d& p) const {
    Cell c;
    for (int a = 0; a < 3; ++a) {
      // Clamped far beyond any real grid, so the conversion is defined for any query box.
      const double x = std::clamp(std::floor((p[a] - origin[a]) / side), -1e15, 1e15);
      c[std::size_t(a)] = long(x);
    }
    return c;
  }
  // The brick at `c`, or -1 if it holds no samples.
  int find(const Cell& c) const {
    const auto it = std::lower_bound(cells.begin(), cells.end(), c);
    return it != cells.end() && *it == c ? int(it - cells.begin()) : -1;
  }
  Box box(int b) const {
    const Cell& c = cells[std::size_t(b)];
    const Vector3d lo = origin + side * Vector3d(double(c[0]), double(c[1]), double(c[2]));
    return {lo, lo + Vector3d::Constant(side)};
  }
};

BrickGrid bucket(const PointMatrix& points, double side) {
  BrickGrid g;
  g.origin = points.colwise().minCoeff().transpose();
  g.side = side;
  const Eigen::Index n = points.rows();
  std::vector<Cell> cell(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) cell[std::size_t(i)] = g.cell_of(points.row(i).transpose());
  // The occupied bricks are few (hundreds): a set of them, not a sort of every sample's cell
  // (auto_brick_size buckets the band once per size it tries). Samples in a row mostly share
  // their brick.
  std::set<Cell> occupied;
  for (std::size_t i = 0; i < cell.size(); ++i)
    if (i == 0 || cell[i] != cell[i - 1]) occupied.insert(cell[i]);
  g.cells.assign(occupied.begin(), occupied.end());
  std::vector<int> brick_of(static_cast<std::size_t>(n));
  g.offsets.assign(g.cells.size() + 1, 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    brick_of[std::size_t(i)] = g.find(cell[std::size_t(i)]);
    ++g.offsets[std::size_t(brick_of[std::size_t(i)]) + 1];
  }
  for (int b = 0; b < g.count(); ++b) g.offsets[std::size_t(b) + 1] += g.offsets[std::size_t(b)];
  g.members.resize(std::size_t(n));
  std::vector<long> fill(g.offsets.begin(), g.offsets.end() - 1);
  for (Eigen::Index i = 0; i < n; ++i)
    g.members[std::size_t(fill[std::size_t(brick_of[std::size_t(i)])]++)] = int(i);
  return g;
}

// The samples inside `box`, ascending. The box's cells are looked up one by one, or, where it
// spans more cells than there are occupied bricks, the occupied bricks are scanned instead.
std::vector<int> gather(const BrickGrid& g, const PointMatrix& points, const Box& box) {
  const Cell lo = g.cell_of(box.min), hi = g.cell_of(box.max);
  std::vector<int> bricks;
  double span = 1;
  for (int a = 0; a < 3; ++a) span *= double(hi[std::size_t(a)] - lo[std::size_t(a)] + 1);
  if (span <= double(g.count())) {
    for (long i = lo[0]; i <= hi[0]; ++i)
      for (long j = lo[1]; j <= hi[1]; ++j)
        for (long k = lo[2]; k <= hi[2]; ++k)
          if (const int b = g.find({i, j, k}); b >= 0) bricks.push_back(b);
  } else {
    for (int b = 0; b < g.count(); ++b) {
      const Cell& c = g.cells[std::size_t(b)];
      bool inside = true;
      for (int a = 0; a < 3; ++a)
        inside = inside && c[std::size_t(a)] >= lo[std::size_t(a)] &&
                 c[std::size_t(a)] <= hi[std::size_t(a)];
      if (inside) bricks.push_back(b);
    }
  }
  std::vector<int> out;
  for (const int b : bricks)
    for (long m = g.offsets[std::size_t(b)]; m < g.offsets[std::size_t(b) + 1]; ++m) {
      const int s = g.members[std::size_t(m)];
      if (box.contains(Vector3d(points.row(s).transpose()))) out.push_back(s);
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

// Retries group the failed samples by cubes of this many spacings.
constexpr double kRetryGroup = 16;
// Retries this deep and deeper put all failed samples in one box that holds the last.
constexpr int kGroupedRetries = 2;

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
    if (std::isfinite(o.weight_cap_inside) || std::isfinite(o.weight_cap_outside)) {
      capped_ = capped_weight_values(s.values, o.weight_cap_inside, o.weight_cap_outside);
      weight_values_ = &capped_;
    }
    max_weight_ =
        o.within ? o.largest_value * o.largest_value : s.values.array().square().maxCoeff();
    whole_block_ = o.within && (o.within->min.array() == -INFINITY).all() &&
                   (o.within->max.array() == INFINITY).all();
    // Twice the largest |value|: a sphere about a point of the box's edge region, grown by the
    // largest weight, stays inside.
    shell_width_ = 2 * std::sqrt(max_weight_);
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
    Box own = grid_.box(brick);
    if (options_.within && !targets.empty()) {
      // A block: the box its targets need, not the brick's (whose halo could leave the block).
      own = {point(targets[0]), point(targets[0])};
      for (int t : targets)
        own.min = own.min.cwiseMin(point(t)), own.max = own.max.cwiseMax(point(t));
    }
    const Vector3d halo = Vector3d::Constant(options_.halo * h_);
    solve({own.min - halo, own.max + halo}, targets, out);
    return out;
  }

 private:
  // Contact points of `targets` (ascending sample indices inside `box`) from the triangulation
  // of the samples in `box`. Targets whose stars it cannot certify are solved again, in small
  // groups (retry), each in a box that holds its orthospheres that failed.
  void solve(const Box& box, const std::vector<int>& targets, BrickOutput& out,
             int depth = 0) const {
    if (targets.empty()) return;
    // (A block is everything only where it is the whole set: unbounded on every side.)
    const bool everything = (!options_.within || whole_block_) && box.contains(all_);
    if (options_.within) {
      const Box block{options_.within->min, options_.within->max};
      const Vector3d shell(Vector3d::Constant(shell_width_));
      if (!block.contains(Box{box.min - shell, box.max + shell}))
        throw HaloTooSmall("the block's halo is too small for its samples' stars");
    }
    // The samples in the box are triangulated; those in a shell around it are only tested
    // against the orthospheres that reach out of the box.
    const Vector3d shell_width = Vector3d::Constant(everything ? 0.0 : shell_width_);
    std::vector<int> local, outside;
    for (int s : gather(grid_, s_.points, {box.min - shell_width, box.max + shell_width}))
      (box.contains(point(s)) ? local : outside).push_back(s);
    const BrickShell shell(s_.points, *weight_values_, outside,
                           {box.min - shell_width, box.max + shell_width}, 2 * h_);
    Samples ls;  // values: the weights' (capped_weight_values)
    Eigen::VectorXd values;
    Triangulation tri;
    std::vector<int> failed;
    std::vector<Box> needs;  // per failed target: the failing spheres (and the target)
    std::vector<char> keep(local.size(), 0);
    if (triangulate_local(local, everything, ls, values, tri)) {
      check_cancel(options_.cancel);
      out.triangulated += long(local.size());
      out.largest = std::max(out.largest, long(local.size()));
      std::vector<signed char> tet_inside(std::size_t(tri.tets.rows()), -1);
      for (std::size_t r = 0, t = 0; r < local.size() && t < targets.size(); ++r) {
        if (local[r] != targets[t]) continue;
        ++t;
        Box need{point(local[r]), point(local[r])};
        if (everything || tri.hidden[r] || certified(ls, tri, r, box, shell, need, tet_inside)) {
          keep[r] = 1;
        } else {
          failed.push_back(local[r]);
          needs.push_back(need);
        }
      }
      const PointMatrix g = vertex_gradients(ls.points, values, tri, gradient_, &keep);
      collect(gradient_contact_points(ls.points, values, g, tri, contact_, &keep), local, out);
    } else {
      failed = targets;
      for (int s : targets) needs.push_back({point(s), point(s)});
    }
    if (failed.empty()) return;
    retry(box, failed, needs, depth, out);
  }

  // Solves the `failed` targets of `box` (a retry at `depth`) again. Each failed target needs a
  // box holding its failing spheres (`needs`) and a halo around itself. The targets are grouped
  // by cubes of kRetryGroup spacings, each group solved in the box its members need, unless
  // those boxes hold more volume than one box for them all: small groups keep a retry's
  // triangulation small, as a thin halo's failures lie along the brick's faces. From
  // kGroupedRetries deep on, the one box also holds `box`, so boxes only grow and the
  // recursion ends. A box that would not grow beyond `box` (a failure that more room does not
  // explain) becomes `box` grown by half its size on every side.
  void retry(const Box& box, const std::vector<int>& failed, const std::vector<Box>& needs,
             int depth, BrickOutput& out) const {
    ++out.retries;
    const Vector3d halo = Vector3d::Constant(options_.halo * h_);
    auto add = [&](Box& to, std::size_t f) {
      to.min = to.min.cwiseMin(needs[f].min - halo);
      to.max = to.max.cwiseMax(needs[f].max + halo);
    };
    auto volume = [](const Box& b) { return (b.max - b.min).prod(); };
    const Box none{Vector3d::Constant(INFINITY), Vector3d::Constant(-INFINITY)};
    std::vector<std::pair<std::array<long, 3>, std::size_t>> keyed(failed.size());
    for (std::size_t f = 0; f < failed.size(); ++f) {
      const Vector3d cell = ((point(failed[f]) - box.min) / (kRetryGroup * h_)).array().floor();
      keyed[f] = {{long(cell.x()), long(cell.y()), long(cell.z())}, f};
    }
    std::sort(keyed.begin(), keyed.end());  // groups in a fixed order, members ascending
    std::vector<Box> boxes;
    std::vector<std::vector<int>> groups;
    Box all = depth < kGroupedRetries ? none : box;
    double grouped = 0;
    for (std::size_t i = 0, j; i < keyed.size(); i = j) {
      boxes.push_back(none);
      groups.emplace_back();
      for (j = i; j < keyed.size() && keyed[j].first == keyed[i].first; ++j) {
        groups.back().push_back(failed[keyed[j].second]);
        add(boxes.back(), keyed[j].second);
        add(all, keyed[j].second);
      }
      grouped += volume(boxes.back());
    }
    if (depth >= kGroupedRetries || grouped >= volume(all)) {
      boxes = {all};
      groups = {failed};
    }
    for (std::size_t g = 0; g < boxes.size(); ++g) {
      Box b = boxes[g];
      if (box.contains(b)) {
        const Vector3d grow = (box.max - box.min) / 2;
        b = {box.min - grow, box.max + grow};
      }
      solve(b, groups[g], out, depth + 1);
    }
  }

  Vector3d point(int s) const { return s_.points.row(s).transpose(); }

  // The local samples' triangulation; false if there is none yet (too few or flat samples).
  // `ls` gets their weights' values, `values` their own.
  bool triangulate_local(const std::vector<int>& local, bool everything, Samples& ls,
                         Eigen::VectorXd& values, Triangulation& tri) const {
    if (local.size() < 4 && !everything) return false;
    ls = samples_at(s_, local);
    values = ls.values;
    if (weight_values_ != &s_.values)
      for (std::size_t r = 0; r < local.size(); ++r)
        ls.values[Eigen::Index(r)] = (*weight_values_)[local[r]];
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
                 const BrickShell& shell, Box& need, std::vector<signed char>& tet_inside) const {
    if (tri.on_hull[r] &&
        !hull_facets_global(ls, tri, int(r), hull_, max_weight_, margin_, box, need))
      return false;
    bool ok = true;
    for (int o = tri.incident_offsets[r]; o < tri.incident_offsets[r + 1]; ++o) {
      const int t = tri.incident_tets[std::size_t(o)];
      signed char& inside = tet_inside[std::size_t(t)];
      // A failure is tested again, so that every target's `need` holds its failing spheres.
      if (inside != 1)
        inside = orthosphere_certified(ls.points, ls.values, tri.tets.row(t).data(), box, &shell,
                                       max_weight_, margin_, need);
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
  Eigen::VectorXd capped_;
  const Eigen::VectorXd* weight_values_ = &s_.values;
  BrickGrid grid_;
  double max_weight_ = 0, margin_ = 0, shell_width_ = 0;
  bool whole_block_ = false;  // `within` is unbounded: the samples are the whole set
  Box all_;
  std::vector<Vector3d> hull_;  // the vertices of every sample's convex hull
};

}  // namespace

Eigen::VectorXd capped_weight_values(const Eigen::VectorXd& values, double inside, double outside) {
  if (!(inside > 0) || !(outside > 0)) throw Error("the weight caps must be positive");
  Eigen::VectorXd out(values.size());
  for (Eigen::Index i = 0; i < values.size(); ++i)
    out[i] = std::min(std::abs(values[i]), values[i] < 0 ? inside : outside);
  return out;
}

double auto_brick_halo(double largest, double spacing) {
  if (!(spacing > 0) || !std::isfinite(spacing)) throw Error("the spacing must be positive");
  // Whole layers: a grid's largest |value| is just under a whole number of spacings.
  return std::ceil(std::abs(largest) / spacing - 1e-6) + 2;
}

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
  if (options.within && !(options.largest_value > 0 && std::isfinite(options.largest_value)))
    throw Error("a block's samples need a positive largest |value| of the whole set");
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
  // (Each sample is one brick's: the keys are distinct, so any sort gives this order.)
  tbb::parallel_sort(order.begin(), order.end());
  result.points.resize(Eigen::Index(order.size()), 3);
  result.normals.resize(Eigen::Index(order.size()), 3);
  result.samples.resize(order.size());
  tbb::parallel_for(std::size_t(0), order.size(), [&](std::size_t r) {
    const auto& [a, row] = order[r].second;
    result.samples[r] = order[r].first;
    result.points.row(Eigen::Index(r)) = outputs[a].kept.points.row(row);
    result.normals.row(Eigen::Index(r)) = outputs[a].kept.normals.row(row);
  });
  if (stats) *stats = st;
  return result;
}

}  // namespace sdfcontour
