#include "sdfcontour/reconstruction/sphere_carving.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>
#include <vector>

#include "contact_points/lattice_spheres.h"
#include "pipeline/uninitialised_allocator.h"
#include "pipeline/work_counter.h"
#include "reconstruction/carving_internal.h"

namespace sdfcontour {

namespace {

// The mesh's vertices bucketed in cubes of side `cell`, by column (i, j) and, within a column,
// by height k: the vertices a ball can hold are found column by column.
class VertexColumns {
 public:
  // Over the vertices `which` of V.
  VertexColumns(const PointMatrix& V, const std::vector<int>& which, double cell) : cell_(cell) {
    origin_ = V.row(which[0]).transpose();
    Eigen::Vector3d top = origin_;
    for (int v : which) {
      origin_ = origin_.cwiseMin(V.row(v).transpose());
      top = top.cwiseMax(V.row(v).transpose());
    }
    const Eigen::Vector3d extent = top - origin_;
    // Keep the column table modest and the heights within an int whatever the spacing: coarser
    // cubes only cost more tests.
    while ((extent[0] / cell_ + 1) * (extent[1] / cell_ + 1) > 6.4e7 || extent[2] / cell_ > 1e9)
      cell_ *= 2;
    for (int a = 0; a < 3; ++a) size_[a] = long(extent[a] / cell_) + 1;
    std::vector<std::pair<long, int>> keyed(which.size(), {0, 0});  // (column, k) key, vertex
    tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t q) {
      const auto c = cell_of(V.row(which[q]).transpose());
      keyed[q] = {(c[1] * size_[0] + c[0]) * size_[2] + c[2], which[q]};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    offsets_.assign(std::size_t(size_[0] * size_[1] + 1), 0);
    heights_.resize(keyed.size());
    vertices_.resize(keyed.size());
    for (std::size_t q = 0; q < keyed.size(); ++q) {
      ++offsets_[std::size_t(keyed[q].first / size_[2]) + 1];
      heights_[q] = int(keyed[q].first % size_[2]);
      vertices_[q] = keyed[q].second;
    }
    std::partial_sum(offsets_.begin(), offsets_.end(), offsets_.begin());
  }

  // Calls f(vertex) for each vertex in a cube that meets the ball (centre p, radius r): per
  // column, only the heights within the ball's chord above the column's nearest point.
  template <class F>
  void for_each_near_ball(const Eigen::Vector3d& p, double r, F&& f) const {
    const Eigen::Vector3d reach = Eigen::Vector3d::Constant(r);
    if ((p + reach - origin_).minCoeff() < 0 ||
        ((p - reach - origin_).array() / cell_ >= Eigen::Array3d(size_[0], size_[1], size_[2]))
            .any())
      return;
    const auto a = cell_of(p - reach), b = cell_of(p + reach);
    for (long j = a[1]; j <= b[1]; ++j)
      for (long i = a[0]; i <= b[0]; ++i) {
        const std::size_t col = std::size_t(j * size_[0] + i);
        if (offsets_[col] == offsets_[col + 1]) continue;
        // The column's nearest point to p across x and y.
        const double dx = gap(p[0] - origin_[0], i), dy = gap(p[1] - origin_[1], j);
        const double rest = r * r - dx * dx - dy * dy;
        if (rest < 0) continue;
        const double chord = std::sqrt(rest);
        const long k0 = cell_of_axis(p[2] - chord, 2), k1 = cell_of_axis(p[2] + chord, 2);
        const auto first = heights_.begin() + long(offsets_[col]),
                   last = heights_.begin() + long(offsets_[col + 1]);
        for (auto it = std::lower_bound(first, last, int(k0)); it != last && *it <= k1; ++it)
          f(vertices_[std::size_t(it - heights_.begin())]);
      }
  }

 private:
  long cell_of_axis(double x, int a) const {
    return std::clamp(long(std::floor((x - origin_[a]) / cell_)), 0L, size_[std::size_t(a)] - 1);
  }
  std::array<long, 3> cell_of(const Eigen::Vector3d& p) const {
    return {cell_of_axis(p[0], 0), cell_of_axis(p[1], 1), cell_of_axis(p[2], 2)};
  }
  // Distance from offset x to cell c's extent along an axis (0 inside it).
  double gap(double x, long c) const {
    return std::max({double(c) * cell_ - x, x - double(c + 1) * cell_, 0.0});
  }

  double cell_;
  Eigen::Vector3d origin_;
  std::array<long, 3> size_{};
  std::vector<std::size_t> offsets_;  // per column (i + size_x j), into heights_ / vertices_
  std::vector<int> heights_, vertices_;
};

// A vertex inside ball `sample`, `depth` short of its sphere.
struct Push {
  int vertex;
  int sample;
  double depth;
};

// A vertex counts as inside a ball when deeper than this many spacings: one pushed onto a
// sphere stays put.
constexpr double kInside = 1e-9;
// Vertices are indexed in cubes of this many spacings (1 and 3 were slower on bunny 256^3).
constexpr double kIndexCell = 2;

// Applies `moves` (per vertex; zero: stay), each scaled back where it would turn a triangle too
// far; returns which vertices moved.
std::vector<char> apply_moves(Mesh& mesh, const PointMatrix& moves, const CarvingOptions& options,
                              CarvingStats& stats) {
  PointMatrix& V = mesh.vertices;
  std::vector<double> factor(std::size_t(V.rows()));
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    factor[std::size_t(v)] = moves.row(v).squaredNorm() > 0 ? 1.0 : 0.0;
  std::vector<char> moved(factor.size(), 0);
  if (std::none_of(factor.begin(), factor.end(), [](double f) { return f > 0; })) return moved;
  stats.held_back += detail::hold_back_turning_triangles(mesh, moves, factor, options);
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    if (factor[std::size_t(v)] > 0) {
      V.row(v) += factor[std::size_t(v)] * moves.row(v);
      moved[std::size_t(v)] = 1;
    }
  return moved;
}

// The indices of the set entries of `flags`.
std::vector<int> set_indices(const std::vector<char>& flags) {
  std::vector<int> out;
  for (std::size_t i = 0; i < flags.size(); ++i)
    if (flags[i]) out.push_back(int(i));
  return out;
}

// Rounds (up to options.passes) pushing the vertices `candidates` out of the balls; only a vertex
// that moved can have entered a ball, so later rounds look at those alone. `first_round`
// (optional) counts the first round's samples, the bulk of the work.
void carve_vertices(Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values,
                    double spacing, const CarvingOptions& options, std::vector<int> candidates,
                    CarvingStats& stats, detail::WorkCounter* first_round = nullptr) {
  for (int round = 0; round < options.passes && !candidates.empty(); ++round) {
    ++stats.passes;
    const PointMatrix moves = detail::deepest_pushes(mesh.vertices, candidates, points, values,
                                                     spacing, round == 0 ? first_round : nullptr);
    candidates = set_indices(apply_moves(mesh, moves, options, stats));
  }
}

// A triangle round moves a feature at most this many spacings: the samples next to the surface
// need far less (all within 0.3 h on the shared meshes), and a longer move would pull a sheet
// towards a part the reconstruction lacks or onto the other side of a thin part (the plane at
// 64^3: moves of 5 h, L1 up 60%).
constexpr double kLongestSideMove = 0.5;

// Rings of triangles around a sample's last nearest triangle searched for its next one.
constexpr int kSeedRings = 1;

// Rounds of the triangle phase (see CarvingOptions::side_passes) over the samples within reach:
// those whose ball the mesh cuts deeper than `slack` (infinite: none) or that lie on the wrong
// side move the mesh's nearest feature. After the first round, only the samples that failed the
// last one or whose nearest triangle moved are checked again. `check`: the samples to check
// first. Returns the vertices it moved and (in `check`) the samples that failed the last round.
std::vector<int> carve_triangles(Mesh& mesh, const detail::VertexTriangles& around,
                                 const PointMatrix& points, const Eigen::VectorXd& values,
                                 double spacing, const CarvingOptions& options, double slack,
                                 std::vector<int>& check, CarvingStats& stats) {
  const TriangleMatrix& F = mesh.triangles;
  std::vector<char> moved(std::size_t(mesh.vertices.rows()), 0);
  // Moves are short (a fraction of a spacing), so after the first round a sample's nearest
  // triangle is sought near its last one.
  std::vector<int> seeds;
  for (int round = 0;; ++round) {
    const std::vector<int> among =
        round > 0 ? detail::triangles_around(mesh, around, seeds, kSeedRings) : std::vector<int>();
    const detail::SideCheck found =
        detail::check_sample_sides(mesh, around, points, values, check, slack,
                                   kLongestSideMove * spacing, round > 0 ? &among : nullptr);
    if (std::isfinite(slack)) {
      if (round == 0) stats.side_violations = found.violations;
      stats.side_violations_left = found.violations;
    }
    stats.wrong_side_left = found.wrong_side;
    if (found.violations == 0 || round == options.side_passes) break;
    const std::vector<char> now = apply_moves(mesh, found.moves, options, stats);
    for (std::size_t v = 0; v < now.size(); ++v) moved[v] |= now[v];
    ++stats.side_passes;
    std::vector<int> next;
    seeds.clear();
    for (std::size_t w = 0; w < check.size(); ++w) {
      const int t = found.nearest[w];
      const bool near_move = t >= 0 && (now[std::size_t(F(t, 0))] || now[std::size_t(F(t, 1))] ||
                                        now[std::size_t(F(t, 2))]);
      if (found.failed[w] || near_move) next.push_back(check[w]), seeds.push_back(t);
    }
    check = std::move(next);
  }
  return set_indices(moved);
}

// (Filled in parallel, as are the moves: these arrays are a vertex's size, 15-22 MB at 256^3.)
using Pushes = detail::Unwritten<Push>;
Pushes no_pushes(Eigen::Index vertices) {
  Pushes best(static_cast<std::size_t>(vertices));
  tbb::parallel_for(std::size_t(0), best.size(), [&](std::size_t v) { best[v] = {-1, -1, 0.0}; });
  return best;
}

// Per vertex with a push (best[v].vertex >= 0), the move onto its ball's sphere; zero elsewhere.
PointMatrix pushes_onto_spheres(const PointMatrix& V, const Pushes& best, const PointMatrix& points,
                                const Eigen::VectorXd& values,
                                const std::vector<double>* allowance = nullptr) {
  PointMatrix moves(V.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), V.rows(), [&](Eigen::Index v) {
    const Push& b = best[std::size_t(v)];
    moves.row(v).setZero();
    if (b.vertex < 0) return;
    const Eigen::Vector3d p = points.row(b.sample).transpose();
    const Eigen::Vector3d from = V.row(v).transpose() - p;
    double r = std::abs(values[b.sample]);
    if (allowance) r -= std::min((*allowance)[std::size_t(v)], r / 2);
    moves.row(v) = (p + from * (r / from.norm()) - V.row(v).transpose()).transpose();
  });
  return moves;
}

}  // namespace

// For each vertex of `which` inside at least one ball, the ball it enters deepest (ties: the
// lower sample), as the displacement onto that ball's sphere; zero elsewhere.
PointMatrix detail::deepest_pushes(const PointMatrix& V, const std::vector<int>& which,
                                   const PointMatrix& points, const Eigen::VectorXd& values,
                                   double spacing, WorkCounter* samples_done) {
  const VertexColumns columns(V, which, kIndexCell * spacing);
  const double inside = kInside * spacing;
  constexpr Eigen::Index kBlock = 4096;
  const Eigen::Index n = points.rows(), blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<Push>> found(static_cast<std::size_t>(blocks));
  tbb::parallel_for(Eigen::Index(0), blocks, [&](Eigen::Index b) {
    auto& out = found[std::size_t(b)];
    if (samples_done) samples_done->add(std::min(n, (b + 1) * kBlock) - b * kBlock);
    for (Eigen::Index s = b * kBlock; s < std::min(n, (b + 1) * kBlock); ++s) {
      const double r = std::abs(values[s]);
      if (!(r > 0)) continue;
      const Eigen::Vector3d p = points.row(s).transpose();
      columns.for_each_near_ball(p, r, [&](int v) {
        const double d2 = (V.row(v).transpose() - p).squaredNorm();
        if (!(d2 < r * r && d2 > 0)) return;
        const double depth = r - std::sqrt(d2);
        if (depth > inside) out.push_back({v, int(s), depth});
      });
    }
  });
  Pushes best = no_pushes(V.rows());
  for (const auto& block : found)
    for (const Push& q : block) {
      Push& b = best[std::size_t(q.vertex)];
      if (b.vertex < 0 || q.depth > b.depth || (q.depth == b.depth && q.sample < b.sample)) b = q;
    }
  return pushes_onto_spheres(V, best, points, values);
}

// Vertices in boxes of this many spacings a side read the balls gathered for their box.
constexpr double kBallListBox = 2;

PointMatrix detail::deepest_pushes(const PointMatrix& V, const std::vector<int>& which,
                                   const Lattice& balls, const std::vector<char>* use,
                                   double spacing, const std::vector<double>* allowance) {
  const double inside = kInside * spacing, cell = kBallListBox * spacing;
  struct Keyed {  // (not a std::pair, whose constructor would zero the list on one thread)
    std::array<long, 3> box;
    int vertex;
    bool operator<(const Keyed& o) const {
      return box < o.box || (box == o.box && vertex < o.vertex);
    }
  };
  detail::Unwritten<Keyed> keyed(which.size());
  tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t q) {
    std::array<long, 3> key;
    for (int a = 0; a < 3; ++a) key[std::size_t(a)] = long(std::floor(V(which[q], a) / cell));
    keyed[q] = {key, which[q]};
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<std::size_t> starts;  // where each box's vertices begin in keyed
  for (std::size_t q = 0; q < keyed.size(); ++q)
    if (q == 0 || keyed[q].box != keyed[q - 1].box) starts.push_back(q);
  starts.push_back(keyed.size());
  Pushes best = no_pushes(V.rows());
  const PointMatrix& points = balls.points();
  tbb::parallel_for(std::size_t(0), starts.size() - 1, [&](std::size_t b) {
    thread_local SphereList list;
    Eigen::Vector3d lo = V.row(keyed[starts[b]].vertex).transpose(), hi = lo;
    for (std::size_t q = starts[b]; q < starts[b + 1]; ++q) {
      lo = lo.cwiseMin(V.row(keyed[q].vertex).transpose());
      hi = hi.cwiseMax(V.row(keyed[q].vertex).transpose());
    }
    if (!(lo.allFinite() && hi.allFinite())) return;
    balls.gather(lo, hi, 0.0, list);
    for (std::size_t q = starts[b]; q < starts[b + 1]; ++q) {
      const int v = keyed[q].vertex;
      const Eigen::Vector3d x = V.row(v).transpose();
      Push& found = best[std::size_t(v)];
      const double deeper_than =
          allowance ? std::max(inside, (*allowance)[std::size_t(v)]) : inside;
      // (The spheres that may hold x found by the list's vectorised scan: a superset of those
      // that the test below takes.)
      for (std::size_t t = list.next_near(x, 0.0, 0); t < list.r.size();
           t = list.next_near(x, 0.0, t + 1)) {
        const double r = list.r[t];
        if (!(r > 0)) continue;
        // The list's centres are the lattice's, which may differ from the samples' own points in
        // the last bit: a hair wider first, then the same test as the ball-driven search.
        const double dx = list.x[t] - x[0], dy = list.y[t] - x[1], dz = list.z[t] - x[2];
        const double reach = r * (1 + 1e-12) + 1e-300;
        if (!((dx * dx + dy * dy) + dz * dz < reach * reach)) continue;
        const long s = list.sample[t];
        if (use && !(*use)[std::size_t(s)]) continue;
        const double d2 = (x - points.row(s).transpose()).squaredNorm();
        if (!(d2 < r * r && d2 > 0)) continue;
        const double depth = r - std::sqrt(d2);
        if (!(depth > deeper_than)) continue;
        if (found.vertex < 0 || depth > found.depth || (depth == found.depth && s < found.sample))
          found = {v, int(s), depth};
      }
    }
  });
  return pushes_onto_spheres(V, best, points, balls.values(), allowance);
}

void detail::carve_vertices_alone(PointMatrix& V, const Lattice& balls,
                                  const std::vector<char>* use, double spacing, int passes,
                                  double max_move, const std::vector<char>* fixed,
                                  const std::vector<double>* allowance) {
  PointMatrix start(V.rows(), 3);
  tbb::parallel_for(Eigen::Index(0), V.rows(), [&](Eigen::Index v) { start.row(v) = V.row(v); });
  std::vector<int> candidates;
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    if (!fixed || !(*fixed)[std::size_t(v)]) candidates.push_back(int(v));
  const double limit2 = max_move * max_move * spacing * spacing;
  for (int round = 0; round < passes && !candidates.empty(); ++round) {
    const PointMatrix moves = deepest_pushes(V, candidates, balls, use, spacing, allowance);
    candidates.clear();
    for (Eigen::Index v = 0; v < V.rows(); ++v) {
      if (!(moves.row(v).squaredNorm() > 0)) continue;
      const Eigen::RowVector3d to = V.row(v) + moves.row(v);
      if ((to - start.row(v)).squaredNorm() > limit2) continue;  // stays: see the header
      V.row(v) = to;
      candidates.push_back(int(v));
    }
  }
}

CarvingStats carve_mesh(Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values,
                        double spacing, const CarvingOptions& options) {
  detail::check_ball_samples("sphere carving", points, values, spacing);
  if (options.passes < 0 || options.halvings < 0 || options.side_passes < 0 ||
      !(options.max_turn_degrees >= 0) || !(options.max_turn_degrees <= 180) ||
      !(options.side_reach >= 0) || !std::isfinite(options.side_reach))
    throw Error(
        "sphere carving: passes, side passes and halvings must be >= 0, the side reach finite "
        "and >= 0, the turn in [0, 180] degrees");
  CarvingStats stats;
  PointMatrix& V = mesh.vertices;
  if (V.rows() == 0 || points.rows() == 0) return stats;
  const PointMatrix start = V;
  std::vector<int> all(std::size_t(V.rows()));
  std::iota(all.begin(), all.end(), 0);
  detail::WorkCounter first_round(options.progress, long(points.rows()));
  carve_vertices(mesh, points, values, spacing, options, std::move(all), stats, &first_round);
  if (options.side_passes > 0) {
    // Triangles off the small balls near the surface and samples onto their sides; then the
    // vertices that moved out of any ball they entered; then, as that can put a sample next to
    // the surface on the wrong side again, its side alone (the few moves left are tiny).
    const detail::VertexTriangles around(mesh);
    const double reach = options.side_reach * spacing;
    std::vector<int> check;
    for (Eigen::Index s = 0; s < values.size(); ++s)
      if (std::abs(values[s]) <= reach) check.push_back(int(s));
    const std::vector<int> moved =
        carve_triangles(mesh, around, points, values, spacing, options, 0.0, check, stats);
    const PointMatrix before = V;
    carve_vertices(mesh, points, values, spacing, options, moved, stats);
    std::vector<int> pushed;  // by the vertex rounds just run
    double longest = 0;
    for (int v : moved)
      if (V.row(v) != before.row(v)) {
        pushed.push_back(v);
        longest = std::max(longest, (V.row(v) - before.row(v)).norm());
      }
    // The samples to check again: those still failing, and those whose balls, grown by the
    // longest push, the pushed vertices' triangles meet (a sample on the surface has none).
    const std::vector<int> near =
        detail::samples_near_vertices(mesh, around, pushed, points, values, reach, longest, 1);
    std::vector<int> again;
    std::set_union(check.begin(), check.end(), near.begin(), near.end(), std::back_inserter(again));
    carve_triangles(mesh, around, points, values, spacing, options,
                    std::numeric_limits<double>::infinity(), again, stats);
  }
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const double d = (V.row(v) - start.row(v)).norm();
    if (d > 0) ++stats.vertices_moved;
    stats.largest_move = std::max(stats.largest_move, d);
  }
  return stats;
}

}  // namespace sdfcontour
