// Nearest-triangle queries over chunks of a mesh, each chunk one CGAL AABB tree
// (nearest_triangles.h).
#include "reconstruction/nearest_triangles.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>

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

}  // namespace

struct NearestTriangles::Chunk {
  Eigen::AlignedBox3d box;
  std::unique_ptr<Tree> tree;
};

NearestTriangles::NearestTriangles(const Mesh& mesh, const std::vector<int>* among,
                                   bool many_queries) {
  std::vector<int> all;
  if (!among) {
    all.resize(std::size_t(mesh.triangles.rows()));
    std::iota(all.begin(), all.end(), 0);
  }
  const std::vector<int>& which = among ? *among : all;
  if (which.empty()) return;
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
  const K::Sphere_3 ball(K::Point_3(c[0], c[1], c[2]), radius * radius);
  for (const auto& chunk : chunks_)
    if (chunk->box.squaredExteriorDistance(c) <= radius * radius && chunk->tree->do_intersect(ball))
      return true;
  return false;
}

}  // namespace sdfcontour::detail
