#include "sdfcontour/reconstruction/side_repair.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "reconstruction/carving_internal.h"
#include "reconstruction/mesh_geometry.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour {

namespace {

// A sample exactly |value| beyond the sheet would sit on the boundary of the ball test: aim this
// much (relative) further.
constexpr double kBeyond = 1e-6;
// A vertex joins a dent only if its normal is within this angle's cosine of the feature's: the
// patch stays on the sheet nearest the sample, not the other side of a thin part. Where every such
// dent fails, the dents are tried again on every vertex within the radius (kAnySheetCos).
constexpr double kSameSheetCos = 0.5;
constexpr double kAnySheetCos = -2;
// A sample in a crease of the mesh can need a dent in each of its sheets: at most this many.
constexpr int kDentsPerSample = 3;

// Two triangles sharing an edge whose unit normals' dot product falls below this have folded.
constexpr double kFoldCos = -0.9;

// A wrong-side sample's nearest point on the mesh is sought within this many spacings (those on
// the shared meshes lie within 0.8).
constexpr double kSearch = 2;

enum class DentShape { Shift, Flatten };

// One try: the geodesic radius, the least cosine of a moved vertex's normal to the feature's,
// the shape, and how far behind the sample the sheet goes.
struct Dent {
  double radius, min_cos;
  DentShape shape;
  double target;
};

// The triangles with a vertex within `radius` of p.
std::vector<int> triangles_near(const Mesh& mesh, const Eigen::Vector3d& p, double radius) {
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  std::vector<char> close(std::size_t(V.rows()), 0);
  for (Eigen::Index v = 0; v < V.rows(); ++v)
    close[std::size_t(v)] = (V.row(v).transpose() - p).squaredNorm() <= radius * radius;
  std::vector<int> out;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    if (close[std::size_t(F(t, 0))] || close[std::size_t(F(t, 1))] || close[std::size_t(F(t, 2))])
      out.push_back(int(t));
  return out;
}

// The vertices within geodesic distance `radius` (along edges) of the feature's point, whose
// normals face along its normal, with their distances (ascending by vertex); Dijkstra from the
// feature's vertices, not through a vertex that faces away.
std::vector<std::pair<int, double>> dent_patch(const Mesh& mesh,
                                               const detail::VertexTriangles& around,
                                               const detail::NearestFeature& at, double radius,
                                               double min_cos) {
  const PointMatrix& V = mesh.vertices;
  const TriangleMatrix& F = mesh.triangles;
  std::unordered_map<int, double> dist;
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  for (int v : at.vertices) {
    const double d = (V.row(v).transpose() - at.point).norm();
    dist[v] = d;
    queue.push({d, v});
  }
  std::unordered_set<int> done;
  std::vector<std::pair<int, double>> out;
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v] || d >= radius || done.count(v)) continue;
    done.insert(v);
    if (detail::unit_vertex_normal(mesh, around, v).dot(at.normal) < min_cos) continue;
    out.push_back({v, d});
    for (int o = around.offsets[std::size_t(v)]; o < around.offsets[std::size_t(v) + 1]; ++o)
      for (int c = 0; c < 3; ++c) {
        const int u = F(around.triangles[std::size_t(o)], c);
        const double du = d + (V.row(u) - V.row(v)).norm();
        const auto it = dist.find(u);
        if (it == dist.end() || du < it->second) {
          dist[u] = du;
          queue.push({du, u});
        }
      }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The triangles around the vertices `patch`, flagged.
std::vector<char> triangles_of(const Mesh& mesh, const detail::VertexTriangles& around,
                               const std::vector<int>& vertices) {
  std::vector<char> flags(std::size_t(mesh.triangles.rows()), 0);
  for (int v : vertices)
    for (int o = around.offsets[std::size_t(v)]; o < around.offsets[std::size_t(v) + 1]; ++o)
      flags[std::size_t(around.triangles[std::size_t(o)])] = 1;
  return flags;
}

class SideRepair {
 public:
  SideRepair(Mesh& mesh, const PointMatrix& points, const Eigen::VectorXd& values, double spacing,
             const SideRepairOptions& options)
      : mesh_(mesh),
        around_(mesh),
        points_(points),
        values_(values),
        spacing_(spacing),
        options_(options) {}

  SideRepairStats run() {
    SideRepairStats stats;
    const double reach = options_.reach * spacing_;
    std::vector<int> check;
    for (Eigen::Index s = 0; s < values_.size(); ++s)
      if (values_[s] != 0 && std::abs(values_[s]) <= reach) check.push_back(int(s));
    const double inf = std::numeric_limits<double>::infinity();
    const detail::SideCheck found =
        detail::check_sample_sides(mesh_, around_, points_, values_, check, inf, inf);
    wrong_.assign(std::size_t(values_.size()), 0);
    std::vector<int> wrong;
    for (std::size_t w = 0; w < check.size(); ++w)
      if (found.failed[w]) wrong.push_back(check[w]), wrong_[std::size_t(check[w])] = 1;
    stats.wrong_side = long(wrong.size());
    std::vector<char> moved(std::size_t(mesh_.vertices.rows()), 0);
    for (std::size_t q = 0; q < wrong.size(); ++q) {
      if (int(q) >= options_.max_samples) break;
      const int s = wrong[q];
      if (!wrong_[std::size_t(s)]) continue;  // an earlier dent put it on its side
      repair(s, moved);
    }
    stats.left = long(std::count(wrong_.begin(), wrong_.end(), 1));
    stats.repaired = stats.wrong_side - stats.left;
    stats.vertices_moved = long(std::count(moved.begin(), moved.end(), 1));
    return stats;
  }

 private:
  // p's nearest feature, among the triangles within `radius` of it.
  detail::NearestFeature nearest(const Eigen::Vector3d& p, double radius) const {
    return detail::nearest_feature(mesh_, around_, p, triangles_near(mesh_, p, radius));
  }

  // Whether two triangles sharing an edge near the moved vertices (`before`: their earlier
  // positions) have folded onto each other (unit normals within kFoldCos of opposite), which the
  // crossing test does not see. Slivers turning over in a flat patch are no fold.
  bool folds(const std::map<int, Eigen::RowVector3d>& before) const {
    const PointMatrix& V = mesh_.vertices;
    const TriangleMatrix& F = mesh_.triangles;
    auto normal = [&](int t, bool earlier) -> Eigen::Vector3d {
      Eigen::Vector3d c[3];
      for (int k = 0; k < 3; ++k) {
        const auto it = before.find(F(t, k));
        c[k] = (earlier && it != before.end() ? it->second : V.row(F(t, k))).transpose();
      }
      return (c[1] - c[0]).cross(c[2] - c[0]).normalized();
    };
    for (const auto& entry : before) {
      const int v = entry.first;
      for (int o = around_.offsets[std::size_t(v)]; o < around_.offsets[std::size_t(v) + 1]; ++o)
        for (int o2 = o + 1; o2 < around_.offsets[std::size_t(v) + 1]; ++o2) {
          const int t = around_.triangles[std::size_t(o)], u = around_.triangles[std::size_t(o2)];
          int shared = 0;
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) shared += F(t, a) == F(u, b);
          if (shared != 2) continue;
          if (normal(t, false).dot(normal(u, false)) < kFoldCos &&
              !(normal(t, true).dot(normal(u, true)) < kFoldCos))
            return true;
        }
    }
    return false;
  }

  // Whether a triangle around `vertices` crosses another of the triangles `among` (which hold
  // every triangle that can reach them): the crossing test on that part of the mesh alone.
  bool crosses(const std::vector<int>& among, const std::vector<int>& vertices) const {
    const std::vector<char> moving = triangles_of(mesh_, around_, vertices);
    std::unordered_map<int, int> index;
    Mesh part;
    part.triangles.resize(Eigen::Index(among.size()), 3);
    std::vector<char> watch(among.size(), 0);
    for (std::size_t q = 0; q < among.size(); ++q) {
      const int t = among[q];
      watch[q] = moving[std::size_t(t)];
      for (int c = 0; c < 3; ++c)
        part.triangles(Eigen::Index(q), c) =
            index.emplace(mesh_.triangles(t, c), int(index.size())).first->second;
    }
    part.vertices.resize(Eigen::Index(index.size()), 3);
    for (const auto& [v, i] : index) part.vertices.row(i) = mesh_.vertices.row(v);
    return !self_intersecting_triangles(part, &watch).empty();
  }

  // Tries dents of growing radius, both shapes, to |value| behind the sample and else half as far
  // (boot 64^3: 2 of its 15 samples need that); keeps the first that works.
  void repair(int s, std::vector<char>& moved) {
    const double r = std::abs(values_[s]);
    for (const double min_cos : {kSameSheetCos, kAnySheetCos})
      for (int doubling = 0; doubling <= options_.radius_doublings; ++doubling) {
        const double radius = options_.radius * spacing_ * std::pow(2.0, doubling);
        for (const DentShape shape : {DentShape::Shift, DentShape::Flatten})
          for (const double depth : {1.0, 0.5})
            if (try_dents(s, {radius, min_cos, shape, depth * r * (1 + kBeyond)}, moved)) return;
      }
  }

  // Dents the sheet nearest to sample s until s lies on its side (a sample in a crease can need
  // a dent in each of its sheets), `target` behind it; keeps the dents if s is then on its side,
  // no sample near them comes to the wrong side and no moved triangle crosses another.
  bool try_dents(int s, const Dent& dent, std::vector<char>& moved) {
    const double radius = dent.radius;
    PointMatrix& V = mesh_.vertices;
    const Eigen::Vector3d p = points_.row(s).transpose();
    const double side = values_[s] > 0 ? 1 : -1;
    const double search = kSearch * spacing_;
    std::map<int, Eigen::RowVector3d> before;
    bool on_side = false;
    for (int step = 0;; ++step) {
      const detail::NearestFeature at = nearest(p, search);
      on_side = at.triangle >= 0 && side * at.height > 0;
      if (at.triangle < 0 || on_side || step == kDentsPerSample) break;
      for (const auto& [v, d] : dent_patch(mesh_, around_, at, radius, dent.min_cos)) {
        const double t = d / radius, w = (1 - t * t) * (1 - t * t);
        // How far v must go along -side * normal: all of the feature's point's way (shift), or
        // its own way to the plane `target` behind p (flatten; none if already behind it).
        const double way = dent.shape == DentShape::Shift
                               ? side * at.height + dent.target
                               : side * (V.row(v).transpose() - p).dot(at.normal) + dent.target;
        if (!(way > 0)) continue;
        before.emplace(v, V.row(v));
        V.row(v) -= (side * w * way) * at.normal.transpose();
      }
    }
    std::vector<int> vertices;
    double longest = 0;
    for (const auto& [v, start] : before) {
      vertices.push_back(v);
      longest = std::max(longest, (V.row(v) - start).norm());
    }
    auto undo = [&] {
      for (const auto& [v, start] : before) V.row(v) = start;
      return false;
    };
    if (vertices.empty() || !on_side || folds(before)) return undo();
    // The samples whose side the dent can change: those the moved triangles swept over, all
    // within `longest` of where they are now. Their nearest points lie within `local` of p.
    std::vector<int> which;
    for (int n : detail::samples_near_vertices(mesh_, around_, vertices, points_, values_,
                                               options_.reach * spacing_, longest, 0))
      if (values_[n] != 0) which.push_back(n);
    if (!std::binary_search(which.begin(), which.end(), s))
      which.insert(std::upper_bound(which.begin(), which.end(), s), s);
    const double local = search + radius + 2 * longest + spacing_;
    const std::vector<int> among = triangles_near(mesh_, points_.row(s).transpose(), local);
    const double inf = std::numeric_limits<double>::infinity();
    const detail::SideCheck after =
        detail::check_sample_sides(mesh_, around_, points_, values_, which, inf, inf, &among);
    std::vector<int> fixed;
    for (std::size_t w = 0; w < which.size(); ++w) {
      const bool wrong = after.failed[w], was = wrong_[std::size_t(which[w])];
      if (wrong && (!was || which[w] == s)) return undo();
      if (!wrong && was) fixed.push_back(which[w]);
    }
    if (crosses(among, vertices)) return undo();
    for (int n : fixed) wrong_[std::size_t(n)] = 0;
    for (int v : vertices) moved[std::size_t(v)] = 1;
    return true;
  }

  Mesh& mesh_;
  const detail::VertexTriangles around_;
  const PointMatrix& points_;
  const Eigen::VectorXd& values_;
  const double spacing_;
  const SideRepairOptions options_;
  std::vector<char> wrong_;  // per sample: on the wrong side now
};

}  // namespace

SideRepairStats repair_sample_sides(Mesh& mesh, const PointMatrix& points,
                                    const Eigen::VectorXd& values, double spacing,
                                    const SideRepairOptions& options) {
  detail::check_ball_samples("side repair", points, values, spacing);
  if (!(options.reach >= 0) || !std::isfinite(options.reach) || !(options.radius > 0) ||
      !std::isfinite(options.radius) || options.radius_doublings < 0 || options.max_samples < 0)
    throw Error(
        "side repair: the reach must be finite and >= 0, the radius finite and > 0, the "
        "doublings and the sample cap >= 0");
  if (mesh.vertices.rows() == 0 || points.rows() == 0) return {};
  return SideRepair(mesh, points, values, spacing, options).run();
}

}  // namespace sdfcontour
