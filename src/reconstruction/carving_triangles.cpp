// The triangle phase of sphere carving: samples whose ball a triangle cuts (not only a vertex),
// or that lie on the wrong side of the mesh, push the nearest feature of the mesh away.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "reconstruction/carving_internal.h"
#include "reconstruction/mesh_geometry.h"
#include "reconstruction/nearest_triangles.h"

namespace sdfcontour::detail {

namespace {

Eigen::Vector3d triangle_normal(const PointMatrix& V, const TriangleMatrix& F, Eigen::Index t) {
  const Eigen::Vector3d a = V.row(F(t, 0)).transpose();
  return (V.row(F(t, 1)).transpose() - a).cross(V.row(F(t, 2)).transpose() - a);
}

// A barycentric coordinate below this counts as zero: the nearest point is on an edge or vertex.
constexpr double kOnFeature = 1e-9;
// A sample pushed exactly onto its sphere would sit on the boundary of the test: aim this much
// (relative) beyond it.
constexpr double kBeyond = 1e-6;

// The outward (pseudo)normal of the feature of triangle t holding the point with barycentric
// coordinates `bary`: the triangle's normal inside it, the sum of the two triangles' unit normals
// on an edge, their angle-weighted sum at a vertex (Baerentzen and Aanaes: the sign of (p - q) .
// n is then the side of p for the nearest point q). Appends the feature's vertices to `feature`.
Eigen::Vector3d feature_normal(const Mesh& mesh, const VertexTriangles& around, Eigen::Index t,
                               const Eigen::Vector3d& bary, std::vector<int>& feature) {
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  auto unit_normal = [&](int u) { return triangle_normal(V, F, u).normalized(); };
  feature.clear();
  for (int c = 0; c < 3; ++c)
    if (bary[c] > kOnFeature) feature.push_back(F(t, c));
  if (feature.size() == 3) return unit_normal(int(t));
  if (feature.empty()) feature.push_back(F(t, 0));  // a degenerate triangle: its first corner
  const int a = feature[0];
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int o = around.offsets[std::size_t(a)]; o < around.offsets[std::size_t(a) + 1]; ++o) {
    const int u = around.triangles[std::size_t(o)];
    if (feature.size() == 2) {
      if (F(u, 0) == feature[1] || F(u, 1) == feature[1] || F(u, 2) == feature[1])
        n += unit_normal(u);
      continue;
    }
    int c = 0;
    while (F(u, c) != a) ++c;
    const Eigen::Vector3d e1 = V.row(F(u, (c + 1) % 3)) - V.row(a),
                          e2 = V.row(F(u, (c + 2) % 3)) - V.row(a);
    const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    n += angle * unit_normal(u);
  }
  return n.normalized();
}

// Above this many queries a tree builds its kd-tree of hints first.
constexpr std::size_t kManyQueries = 2000;

// A vertex's requested move, from sample `sample`, `length` long.
// A checked sample's move of a vertex: per vertex, the first request (one int: 40 bytes a vertex
// were a tenth of a 1024^3 brick's side check).
struct Request {
  int sample = -1;
  bool wrong_side = false;
  double length = 0;
  // Whether this request goes before r: a wrong side first, then the longer, then the lower sample.
  bool before(const Request& r) const {
    if (r.sample < 0 || wrong_side != r.wrong_side) return r.sample < 0 || wrong_side;
    return length > r.length || (length == r.length && sample < r.sample);
  }
};

}  // namespace

void check_ball_samples(const char* what, const PointMatrix& points, const Eigen::VectorXd& values,
                        double spacing) {
  const std::string name(what);
  if (points.rows() != values.size())
    throw Error(name + ": " + std::to_string(points.rows()) + " points but " +
                std::to_string(values.size()) + " values");
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw Error(name + ": the spacing must be positive and finite");
  if (!values.allFinite() || !points.allFinite())
    throw Error(name + ": the samples must be finite");
}

VertexTriangles::VertexTriangles(const Mesh& mesh, const std::vector<char>* skip) {
  if (mesh.vertices.rows() >= std::numeric_limits<int>::max() ||
      3 * mesh.triangles.rows() >= std::numeric_limits<int>::max())
    throw Error("too many vertices or triangles for one mesh piece (2^31 corners)");
  if (skip && skip->size() != std::size_t(mesh.vertices.rows()))
    throw Error("one skip flag per vertex is needed");
  const TriangleMatrix& F = mesh.triangles;
  const std::size_t count = std::size_t(mesh.vertices.rows());
  // A counting sort in parallel: the corners counted per vertex, each placed at its vertex's next
  // place, then each vertex's triangles in ascending order (whatever the order of placing).
  std::vector<std::atomic<int>> next(count);
  tbb::parallel_for(std::size_t(0), count,
                    [&](std::size_t v) { next[v].store(0, std::memory_order_relaxed); });
  auto counted = [&](int v) { return !skip || !(*skip)[std::size_t(v)]; };
  tbb::parallel_for(Eigen::Index(0), F.rows(), [&](Eigen::Index t) {
    for (int c = 0; c < 3; ++c)
      if (counted(F(t, c))) next[std::size_t(F(t, c))].fetch_add(1, std::memory_order_relaxed);
  });
  offsets.resize(count + 1);
  offsets[0] = 0;
  for (std::size_t v = 0; v < count; ++v) {
    offsets[v + 1] = offsets[v] + next[v].load(std::memory_order_relaxed);
    next[v].store(offsets[v], std::memory_order_relaxed);
  }
  triangles.resize(std::size_t(offsets.back()));
  tbb::parallel_for(Eigen::Index(0), F.rows(), [&](Eigen::Index t) {
    for (int c = 0; c < 3; ++c)
      if (counted(F(t, c)))
        triangles[std::size_t(next[std::size_t(F(t, c))].fetch_add(1, std::memory_order_relaxed))] =
            int(t);
  });
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t v) {
    std::sort(triangles.begin() + offsets[v], triangles.begin() + offsets[v + 1]);
  });
}

std::vector<int> triangles_around(const Mesh& mesh, const VertexTriangles& around,
                                  const std::vector<int>& seeds, int rings) {
  const TriangleMatrix& F = mesh.triangles;
  std::vector<char> in(std::size_t(F.rows()), 0);
  std::vector<int> frontier;
  for (int t : seeds)
    if (t >= 0 && !in[std::size_t(t)]) in[std::size_t(t)] = 1, frontier.push_back(t);
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<int> next;
    for (int t : frontier)
      for (int c = 0; c < 3; ++c) {
        const int v = F(t, c);
        for (int o = around.offsets[std::size_t(v)]; o < around.offsets[std::size_t(v) + 1]; ++o) {
          const int u = around.triangles[std::size_t(o)];
          if (!in[std::size_t(u)]) in[std::size_t(u)] = 1, next.push_back(u);
        }
      }
    frontier = std::move(next);
  }
  std::vector<int> out;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    if (in[std::size_t(t)]) out.push_back(int(t));
  return out;
}

std::vector<int> samples_near_vertices(const Mesh& mesh, const VertexTriangles& around,
                                       const std::vector<int>& vertices, const PointMatrix& points,
                                       const Eigen::VectorXd& values, double reach, double grow,
                                       double ball) {
  std::vector<int> seeds;
  for (int v : vertices)
    for (int o = around.offsets[std::size_t(v)]; o < around.offsets[std::size_t(v) + 1]; ++o)
      seeds.push_back(around.triangles[std::size_t(o)]);
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  if (seeds.empty()) return {};
  const NearestTriangles tree(mesh, &seeds, false);
  std::vector<char> near(std::size_t(values.size()), 0);
  tbb::parallel_for(Eigen::Index(0), values.size(), [&](Eigen::Index s) {
    const double r = std::abs(values[s]);
    if (!(r <= reach)) return;
    near[std::size_t(s)] = tree.meets_ball(points.row(s).transpose(), ball * r + grow);
  });
  std::vector<int> out;
  for (std::size_t s = 0; s < near.size(); ++s)
    if (near[s]) out.push_back(int(s));
  return out;
}

// Scales each vertex's move (factor 1, halved, then 0) until no triangle's normal turns by more
// than the allowed angle; returns the vertices held back.
long hold_back_turning_triangles(const Mesh& mesh, const PointMatrix& moves,
                                 std::vector<double>& factor, const CarvingOptions& options) {
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  std::vector<Eigen::Index> moving;  // triangles with a moving vertex
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    if (factor[std::size_t(F(t, 0))] > 0 || factor[std::size_t(F(t, 1))] > 0 ||
        factor[std::size_t(F(t, 2))] > 0)
      moving.push_back(t);
  std::vector<Eigen::Vector3d> before(moving.size());
  for (std::size_t q = 0; q < moving.size(); ++q) before[q] = triangle_normal(V, F, moving[q]);
  const double min_cos = std::cos(options.max_turn_degrees * M_PI / 180);
  std::vector<char> turned(moving.size());
  std::vector<char> held(std::size_t(V.rows()), 0);
  for (int round = 0;; ++round) {
    tbb::parallel_for(std::size_t(0), moving.size(), [&](std::size_t q) {
      const Eigen::Index t = moving[q];
      Eigen::Matrix3d corners;
      for (int c = 0; c < 3; ++c) {
        const int v = F(t, c);
        corners.col(c) = (V.row(v) + factor[std::size_t(v)] * moves.row(v)).transpose();
      }
      const Eigen::Vector3d after =
          (corners.col(1) - corners.col(0)).cross(corners.col(2) - corners.col(0));
      turned[q] = !(before[q].dot(after) >= min_cos * before[q].norm() * after.norm());
    });
    bool any = false;
    for (std::size_t q = 0; q < moving.size(); ++q) {
      if (!turned[q]) continue;
      for (int c = 0; c < 3; ++c) {
        const std::size_t v = std::size_t(F(moving[q], c));
        if (factor[v] == 0) continue;
        factor[v] = round < options.halvings ? factor[v] / 2 : 0;
        held[v] = 1;
        any = true;
      }
    }
    if (!any) break;
  }
  return long(std::count(held.begin(), held.end(), 1));
}

// The feature of triangle t holding q, p's nearest point on the mesh.
static NearestFeature feature_at(const Mesh& mesh, const VertexTriangles& around, int t,
                                 const Eigen::Vector3d& q, const Eigen::Vector3d& p) {
  NearestFeature out;
  out.triangle = t;
  out.point = q;
  out.normal = feature_normal(mesh, around, t, barycentric(mesh, t, q), out.vertices);
  out.height = (p - q).dot(out.normal);
  return out;
}

NearestFeature nearest_feature(const Mesh& mesh, const VertexTriangles& around,
                               const Eigen::Vector3d& p, const std::vector<int>& among) {
  if (among.empty()) return {};
  const NearestTriangles::Hit nearest = NearestTriangles(mesh, &among, false).closest(p);
  return feature_at(mesh, around, nearest.triangle, nearest.point, p);
}

SideCheck check_sample_sides(const Mesh& mesh, const VertexTriangles& around,
                             const PointMatrix& points, const Eigen::VectorXd& values,
                             const std::vector<int>& which, double slack, double longest,
                             const std::vector<int>* among) {
  SideCheck out;
  out.moves = PointMatrix::Zero(mesh.vertices.rows(), 3);
  if (mesh.triangles.rows() == 0 || which.empty()) return out;
  const PointMatrix& V = mesh.vertices;
  if (among && among->empty()) return out;
  // The kd-trees of hints pay off over many queries, not over the few of later rounds.
  const NearestTriangles tree(mesh, among, which.size() > kManyQueries);
  // Per checked sample: the feature's vertices and the move asked of them (empty if none).
  std::vector<std::vector<int>> features(which.size());
  std::vector<Eigen::Vector3d> asked(which.size());
  std::vector<char> wrong(which.size(), 0);
  out.nearest.assign(which.size(), -1);
  out.failed.assign(which.size(), 0);
  std::vector<double> distance(which.size(), 0.0);
  tbb::parallel_for(std::size_t(0), which.size(), [&](std::size_t w) {
    const int s = which[w];
    const double r = std::abs(values[s]);
    if (!(r > 0)) return;
    const Eigen::Vector3d p = points.row(s).transpose();
    const NearestTriangles::Hit nearest = tree.closest(p);
    const int t = nearest.triangle;
    out.nearest[w] = t;
    distance[w] = (p - nearest.point).norm();
    NearestFeature at = feature_at(mesh, around, t, nearest.point, p);
    const Eigen::Vector3d q = at.point, n = at.normal;
    std::vector<int>& feature = at.vertices;
    const double side = values[s] > 0 ? 1 : -1, height = at.height;
    wrong[w] = !(side * height > 0);
    if (!wrong[w] && (p - q).norm() >= r - slack) return;
    out.failed[w] = 1;
    // Move the feature along n so that p would lie r (and a little) beyond it on its own side.
    asked[w] = (height - side * r * (1 + kBeyond)) * n;
    // A longer move is no local correction (a missing thin part, or the other side's sheet):
    // it counts, but moves nothing.
    if (asked[w].norm() > longest) feature.clear();
    features[w] = std::move(feature);
  });
  // Per vertex: the checked sample (its place in `which`) whose request goes first, or -1.
  std::vector<int> best(std::size_t(V.rows()), -1);
  auto request = [&](int w) {
    return w < 0 ? Request{}
                 : Request{which[std::size_t(w)], bool(wrong[std::size_t(w)]),
                           asked[std::size_t(w)].norm()};
  };
  for (std::size_t w = 0; w < which.size(); ++w) {
    out.farthest = std::max(out.farthest, distance[w]);
    if (!out.failed[w]) continue;
    ++out.violations;
    out.wrong_side += wrong[w];
    if (features[w].empty()) continue;
    const Request asks = request(int(w));
    for (int v : features[w])
      if (asks.before(request(best[std::size_t(v)]))) best[std::size_t(v)] = int(w);
  }
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    if (best[std::size_t(v)] >= 0)
      out.moves.row(v) = asked[std::size_t(best[std::size_t(v)])].transpose();
  return out;
}

}  // namespace sdfcontour::detail
