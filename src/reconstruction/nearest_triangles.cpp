// Nearest-triangle queries over a uniform grid of a mesh's triangles, or over chunks of it, each
// chunk one CGAL AABB tree (nearest_triangles.h).
#include "reconstruction/nearest_triangles.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include "reconstruction/triangle_cells.h"

namespace sdfcontour::detail {

namespace {

using K = CGAL::Simple_cartesian<double>;

// A mesh triangle by its index (CGAL's AABBPrimitiveWithSharedData): the tree keeps the index
// alone and reads the corners from the mesh, where a copied K::Triangle_3 per primitive was 72
// bytes more per triangle (the side checks build these trees over a brick's whole mesh).
class MeshTriangle {
 public:
  using Id = int;
  using Point = K::Point_3;
  using Datum = K::Triangle_3;
  using Shared_data = const Mesh*;

  MeshTriangle() = default;
  MeshTriangle(std::vector<int>::const_iterator t, const Mesh*) : id_(*t) {}
  Id id() const { return id_; }
  Datum datum(const Mesh* mesh) const {
    return Datum(corner(mesh, 0), corner(mesh, 1), corner(mesh, 2));
  }
  Point reference_point(const Mesh* mesh) const { return corner(mesh, 0); }
  static Shared_data construct_shared_data(const Mesh* mesh) { return mesh; }

 private:
  Point corner(const Mesh* mesh, int c) const {
    const auto v = mesh->vertices.row(mesh->triangles(id_, c));
    return Point(v[0], v[1], v[2]);
  }
  Id id_ = -1;
};

using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, MeshTriangle>>;

// Chunks hold at least this many triangles, and there are at most kMostChunks of them: enough
// chunks to build on every core, few enough that a query's walk over their boxes stays cheap.
constexpr std::size_t kLeastChunk = 32768;
constexpr std::size_t kMostChunks = 64;

// The 30-bit Morton code of a point quantised to 1024 steps per axis of `box`.
std::uint32_t morton(const Eigen::Vector3d& p, const Eigen::AlignedBox3d& box) {
  const Eigen::Vector3d extent = (box.max() - box.min()).cwiseMax(1e-300);
  std::uint32_t code = 0;
  for (int a = 0; a < 3; ++a) {
    const double unit = (p[a] - box.min()[a]) / extent[a];
    const auto q = std::uint32_t(std::clamp(unit * 1024.0, 0.0, 1023.0));
    for (int bit = 0; bit < 10; ++bit) code |= ((q >> bit) & 1u) << (3 * bit + a);
  }
  return code;
}

// The point of triangle abc nearest p: CGAL's projection onto a triangle (the trees' own; a
// degenerate triangle as its longest side).
Eigen::Vector3d nearest_on_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c, const Eigen::Vector3d& p) {
  auto point = [](const Eigen::Vector3d& x) { return K::Point_3(x[0], x[1], x[2]); };
  const K::Point_3 q = K().construct_projected_point_3_object()(
      K::Triangle_3(point(a), point(b), point(c)), point(p));
  return {q.x(), q.y(), q.z()};
}

// Rings of cells that a nearest-triangle query reads cell by cell, nearest first; beyond them,
// whole blocks.
constexpr int kRings = 2;

// The uniform grid is taken where the triangles' sizes are alike (the local reconstruction's
// meshes): its cells are the largest triangle's box, so a triangle meets at most 8; where the
// largest is more than this many times the mean, CGAL's trees.
constexpr double kAlikeSizes = 8;
// At most this many columns of cells (else the trees).
constexpr double kMostColumns = double(1 << 22);

}  // namespace

struct NearestTriangles::Chunk {
  Eigen::AlignedBox3d box;
  std::unique_ptr<Tree> tree;
};

// The triangles listed per cell (each in every cell its box meets), with a ball around each.
struct NearestTriangles::Grid {
  // The grid over `which`, or null where their sizes are not alike (or too many columns).
  static std::unique_ptr<Grid> make(const Mesh& mesh, const std::vector<int>& which);

  Grid(const Mesh& m, const std::vector<int>& which, const CellGrid& grid,
       const std::vector<TriangleCells::Range>& ranges, std::vector<Eigen::Vector4d> b)
      : mesh(&m), triangles(which), balls(std::move(b)), cells(grid, ranges) {}

  const Mesh* mesh = nullptr;
  std::vector<int> triangles;          // the triangles searched
  std::vector<Eigen::Vector4d> balls;  // per triangle searched: a ball holding it
  TriangleCells cells;                 // listing places in `triangles`

  Eigen::Vector3d corner(int t, int c) const {
    return mesh->vertices.row(mesh->triangles(t, c)).transpose();
  }
  Hit closest(const Eigen::Vector3d& p) const;
  bool meets_ball(const Eigen::Vector3d& c, double radius) const;

  // The distance from p to the nearest cell outside r (infinite if it is the grid).
  double beyond(const Eigen::Vector3d& p, const TriangleCells::Range& r) const {
    const CellGrid& g = cells.grid();
    double d = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (r.lo[std::size_t(a)] > 0)
        d = std::min(d, std::max(0.0, p[a] - (g.origin[a] + r.lo[std::size_t(a)] * g.cell)));
      if (r.hi[std::size_t(a)] < g.n[std::size_t(a)] - 1)
        d = std::min(d, std::max(0.0, g.origin[a] + (r.hi[std::size_t(a)] + 1) * g.cell - p[a]));
    }
    return d;
  }
};

NearestTriangles::Hit NearestTriangles::Grid::closest(const Eigen::Vector3d& p) const {
  Hit hit;
  const CellGrid& g = cells.grid();
  const std::array<int, 3> at = g.cube_of(p);
  double best = INFINITY;
  // A triangle whose ball lies farther than the best cannot be nearer (a hair's slack for the
  // rounding: ties are still compared).
  auto visit = [&](int w) {
    const int t = triangles[std::size_t(w)];
    const Eigen::Vector4d& ball = balls[std::size_t(w)];
    if (best < INFINITY) {
      const double reach = (std::sqrt(best) + ball[3]) * (1 + 1e-9);
      if ((p - ball.head<3>()).squaredNorm() > reach * reach) return;
    }
    const Eigen::Vector3d q = nearest_on_triangle(corner(t, 0), corner(t, 1), corner(t, 2), p);
    const double d = (q - p).squaredNorm();
    if (d < best || (d == best && t < hit.triangle)) {
      best = d;
      hit.triangle = t;
      hit.point = q;
    }
  };
  cells.for_each_in({at, at}, visit);  // (its own cell first: a near best bounds the rest)
  // Then the rings of cells around it up to kRings: each cell nearest first, and only where it
  // lies within the best distance (a hair more, for the rounding: a triangle listed there meets
  // it, so none nearer, nor a tie, is left out). A near best reads a few of their 124 cells. The
  // answer is the least distance and, among ties, the least index, whatever the order of visits.
  const double magnitude = 1 + p.cwiseAbs().maxCoeff() + g.origin.cwiseAbs().maxCoeff() +
                           g.cell * *std::max_element(g.n.begin(), g.n.end());
  auto block = [&](int reach) {
    TriangleCells::Range r;
    for (std::size_t a = 0; a < 3; ++a) {
      r.lo[a] = std::max(0, at[a] - reach);
      r.hi[a] = std::min(g.n[a] - 1, at[a] + reach);
    }
    return r;
  };
  auto done = [&](const TriangleCells::Range& r) {
    const double outside = beyond(p, r);
    return !std::isfinite(outside) || best <= outside * outside;
  };
  struct Near {
    double d2;
    std::array<int, 3> cube;
  };
  thread_local std::vector<Near> ring;
  for (int reach = 1; reach <= kRings; ++reach) {
    const TriangleCells::Range r = block(reach);
    ring.clear();
    for (int i = r.lo[0]; i <= r.hi[0]; ++i)
      for (int j = r.lo[1]; j <= r.hi[1]; ++j)
        for (int k = r.lo[2]; k <= r.hi[2]; ++k) {
          if (std::max({std::abs(i - at[0]), std::abs(j - at[1]), std::abs(k - at[2])}) < reach)
            continue;  // an inner ring's
          const std::array<int, 3> c{i, j, k};
          double d2 = 0;
          for (std::size_t a = 0; a < 3; ++a) {
            const double lo = g.origin[a] + c[a] * g.cell, hi = lo + g.cell;
            const double out = p[a] < lo ? lo - p[a] : (p[a] > hi ? p[a] - hi : 0.0);
            d2 += out * out;
          }
          ring.push_back({d2, c});
        }
    std::sort(ring.begin(), ring.end(), [](const Near& x, const Near& y) {
      return x.d2 < y.d2 || (x.d2 == y.d2 && x.cube < y.cube);
    });
    for (const Near& c : ring) {
      const double within = std::sqrt(best) * (1 + 1e-9) + 1e-12 * magnitude;
      if (c.d2 > within * within) break;
      cells.for_each_in({c.cube, c.cube}, visit);
    }
    if (done(r)) return hit;
  }
  // Farther (few triangles near the point): blocks twice as wide each time.
  for (int reach = 2 * kRings;; reach *= 2) {
    const TriangleCells::Range r = block(reach);
    cells.for_each_in(r, visit);
    if (done(r)) return hit;
  }
}

bool NearestTriangles::Grid::meets_ball(const Eigen::Vector3d& c, double radius) const {
  bool met = false;
  const double slack = 1 + 1e-9;
  const Eigen::Vector3d reach = Eigen::Vector3d::Constant(radius);
  cells.for_each_in(cells.range(c - reach, c + reach), [&](int w) {
    const Eigen::Vector4d& ball = balls[std::size_t(w)];
    const double apart = (radius + ball[3]) * slack;
    if (met || (c - ball.head<3>()).squaredNorm() > apart * apart) return;
    const int t = triangles[std::size_t(w)];
    met = (nearest_on_triangle(corner(t, 0), corner(t, 1), corner(t, 2), c) - c).squaredNorm() <=
          radius * radius;
  });
  return met;
}

NearestTriangles::NearestTriangles(const Mesh& mesh, const std::vector<int>* among,
                                   bool many_queries) {
  std::vector<int> all;
  if (!among) {
    all.resize(std::size_t(mesh.triangles.rows()));
    std::iota(all.begin(), all.end(), 0);
  }
  const std::vector<int>& which = among ? *among : all;
  if (which.empty()) return;
  grid_ = Grid::make(mesh, which);
  if (grid_) return;
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  auto centroid = [&](int t) {
    return ((V.row(F(t, 0)) + V.row(F(t, 1)) + V.row(F(t, 2))) / 3.0).transpose().eval();
  };
  Eigen::AlignedBox3d bounds;
  for (int t : which) bounds.extend(centroid(t));
  std::vector<std::pair<std::uint32_t, int>> order(which.size());
  tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t i) {
    order[i] = {morton(centroid(which[i]), bounds), which[i]};
  });
  tbb::parallel_sort(order.begin(), order.end());
  const std::size_t size = std::max(kLeastChunk, (which.size() + kMostChunks - 1) / kMostChunks);
  const std::size_t count = (which.size() + size - 1) / size;
  chunks_.resize(count);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t c) {
    auto chunk = std::make_unique<Chunk>();
    const std::size_t end = std::min(which.size(), (c + 1) * size);
    std::vector<int> triangles;
    for (std::size_t i = c * size; i < end; ++i) {
      const int t = order[i].second;
      triangles.push_back(t);
      for (int k = 0; k < 3; ++k) chunk->box.extend(V.row(F(t, k)).transpose());
    }
    chunk->tree = std::make_unique<Tree>(triangles.cbegin(), triangles.cend(), &mesh);
    chunk->tree->build();
    if (many_queries)
      chunk->tree->accelerate_distance_queries();
    else
      chunk->tree->do_not_accelerate_distance_queries();
    chunks_[c] = std::move(chunk);
  });
}

NearestTriangles::~NearestTriangles() = default;

NearestTriangles::Hit NearestTriangles::closest(const Eigen::Vector3d& p) const {
  Hit hit;
  if (grid_) return grid_->closest(p);
  if (chunks_.empty()) return hit;
  // Chunks by the distance to their boxes (ties: the lower chunk).
  std::vector<std::pair<double, std::size_t>> near(chunks_.size());
  for (std::size_t c = 0; c < chunks_.size(); ++c)
    near[c] = {chunks_[c]->box.squaredExteriorDistance(p), c};
  std::sort(near.begin(), near.end());
  double best = std::numeric_limits<double>::infinity();
  const K::Point_3 q(p[0], p[1], p[2]);
  for (const auto& [box_distance, c] : near) {
    if (box_distance >= best) break;
    const Chunk& chunk = *chunks_[c];
    const auto [point, primitive] = chunk.tree->closest_point_and_primitive(q);
    const double d = CGAL::squared_distance(q, point);
    if (d < best) {
      best = d;
      hit.triangle = primitive;
      hit.point = Eigen::Vector3d(point.x(), point.y(), point.z());
    }
  }
  return hit;
}

bool NearestTriangles::meets_ball(const Eigen::Vector3d& c, double radius) const {
  if (grid_) return grid_->meets_ball(c, radius);
  const K::Sphere_3 ball(K::Point_3(c[0], c[1], c[2]), radius * radius);
  for (const auto& chunk : chunks_)
    if (chunk->box.squaredExteriorDistance(c) <= radius * radius && chunk->tree->do_intersect(ball))
      return true;
  return false;
}

std::unique_ptr<NearestTriangles::Grid> NearestTriangles::Grid::make(
    const Mesh& mesh, const std::vector<int>& which) {
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  auto box = [&](int t) {
    Eigen::AlignedBox3d b;
    for (int c = 0; c < 3; ++c) b.extend(V.row(F(t, c)).transpose());
    return b;
  };
  // The largest and the mean of the triangles' largest box sides, and their box.
  struct Sizes {
    double largest = 0, sum = 0;
    Eigen::AlignedBox3d box;
  };
  Sizes sizes;
  for (int t : which) {
    const Eigen::AlignedBox3d b = box(t);
    const double side = b.sizes().maxCoeff();
    sizes.largest = std::max(sizes.largest, side);
    sizes.sum += side;
    sizes.box.extend(b);
  }
  const double mean = sizes.sum / double(which.size());
  if (!(sizes.largest > 0) || !(sizes.largest <= kAlikeSizes * mean) ||
      !sizes.box.sizes().allFinite())
    return nullptr;
  const CellGrid grid =
      CellGrid::over(sizes.box.min(), sizes.box.max(), sizes.largest, kMostColumns);
  if (grid.cell != sizes.largest) return nullptr;
  std::vector<TriangleCells::Range> ranges(which.size());
  std::vector<Eigen::Vector4d> balls(which.size());
  tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t w) {
    const Eigen::AlignedBox3d b = box(which[w]);
    const Eigen::Vector3d centre = b.center();
    double radius = 0;
    for (int c = 0; c < 3; ++c)
      radius = std::max(radius, (V.row(F(which[w], c)).transpose() - centre).norm());
    balls[w] << centre, radius;
    ranges[w] = {grid.cube_of(b.min()), grid.cube_of(b.max())};
  });
  return std::make_unique<Grid>(mesh, which, grid, ranges, std::move(balls));
}

}  // namespace sdfcontour::detail
