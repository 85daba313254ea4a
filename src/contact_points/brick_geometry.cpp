#include "contact_points/brick_geometry.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>

#include "contact_points/brick_shell.h"

namespace sdfcontour {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

Point point(const Eigen::Vector3d& p) {
  return Point(p.x(), p.y(), p.z());
}

std::vector<Point> extreme_points(const std::vector<Point>& points) {
  std::vector<Point> out;
  // extreme_points_3 needs a full-dimensional set; fewer than 5 points are all kept (a
  // superset of the hull's vertices only makes the facet test stricter).
  if (points.size() < 5) return points;
  try {
    CGAL::extreme_points_3(points, std::back_inserter(out));
  } catch (...) {
    return points;
  }
  return out;
}

}  // namespace

std::vector<Eigen::Vector3d> convex_hull_vertices(const PointMatrix& points,
                                                  const std::vector<std::vector<int>>& buckets) {
  std::vector<std::vector<Point>> per_bucket(buckets.size());
  tbb::parallel_for(std::size_t(0), buckets.size(), [&](std::size_t b) {
    // A point between two others with its x and y is no hull vertex: only each such column's
    // two ends go to the hull search (a grid's band of 8 crosses a column in runs of 17 samples,
    // all on the grid's degenerate planes, which the hull search is slow on).
    std::vector<std::array<double, 3>> own;
    own.reserve(buckets[b].size());
    for (int r : buckets[b]) own.push_back({points(r, 0), points(r, 1), points(r, 2)});
    std::sort(own.begin(), own.end());
    std::vector<Point> ends;
    for (std::size_t i = 0; i < own.size(); ++i) {
      const bool first = i == 0 || own[i][0] != own[i - 1][0] || own[i][1] != own[i - 1][1];
      const bool last =
          i + 1 == own.size() || own[i][0] != own[i + 1][0] || own[i][1] != own[i + 1][1];
      if (first || last) ends.push_back(Point(own[i][0], own[i][1], own[i][2]));
    }
    per_bucket[b] = extreme_points(ends);
  });
  std::vector<Point> all;
  for (const auto& v : per_bucket) all.insert(all.end(), v.begin(), v.end());
  std::vector<Eigen::Vector3d> out;
  for (const Point& p : extreme_points(all)) out.emplace_back(p.x(), p.y(), p.z());
  return out;
}

HullFacet classify_hull_facet(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c, const Eigen::Vector3d& inner,
                              const std::vector<Eigen::Vector3d>& hull) {
  const Point pa = point(a), pb = point(b), pc = point(c);
  const CGAL::Orientation in = CGAL::orientation(pa, pb, pc, point(inner));
  if (in == CGAL::COPLANAR) return HullFacet::NotGlobal;
  HullFacet out = HullFacet::Global;
  for (const Eigen::Vector3d& q : hull) {
    if (q == a || q == b || q == c) continue;
    const CGAL::Orientation side = CGAL::orientation(pa, pb, pc, point(q));
    if (side == CGAL::COPLANAR)
      out = HullFacet::InGlobalFace;
    else if (side != in)
      return HullFacet::NotGlobal;
  }
  return out;
}

bool exact_orthocentre(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d, const Eigen::Vector4d& w,
                       Eigen::Vector3d& centre) {
  using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
  auto at = [](const Eigen::Vector3d& p) { return Exact::Point_3(p.x(), p.y(), p.z()); };
  if (CGAL::orientation(at(a), at(b), at(c), at(d)) == CGAL::COPLANAR) return false;
  const Exact::Weighted_point_3 pa(at(a), w[0]), pb(at(b), w[1]), pc(at(c), w[2]), pd(at(d), w[3]);
  const Exact::Point_3 o = Exact().construct_weighted_circumcenter_3_object()(pa, pb, pc, pd);
  centre = {CGAL::to_double(o.x()), CGAL::to_double(o.y()), CGAL::to_double(o.z())};
  return centre.allFinite();
}

namespace {
using Eigen::Vector3d;
using Box = BrickBox;
}  // namespace

bool sphere_inside(const Vector3d& c, double reach2, const Box& box, double margin, Box& need) {
  if (!std::isfinite(reach2) || !c.allFinite()) return false;
  if (reach2 <= -margin * margin) return true;  // an imaginary sphere: no sample can violate it
  const double reach = std::sqrt(std::max(reach2, 0.0)) + margin;
  if (box.depth(c) > reach) return true;
  need.min = need.min.cwiseMin(c - Vector3d::Constant(reach));
  need.max = need.max.cwiseMax(c + Vector3d::Constant(reach));
  return false;
}

bool orthosphere_certified(const PointMatrix& p, const Eigen::VectorXd& values, const int* v,
                           const Box& box, const BrickShell* shell, double max_weight,
                           double margin, Box& need) {
  auto w = [&](int i) { return values[i] * values[i]; };
  const Vector3d p0 = p.row(v[0]).transpose();
  // The orthocentre c = p0 + x solves 2 d_r . x = |d_r|^2 - w_r + w_0 (r = 1..3), by Cramer's
  // rule with cross products.
  Vector3d d[3];
  double b[3];
  for (int r = 0; r < 3; ++r) {
    d[r] = p.row(v[r + 1]).transpose() - p0;
    b[r] = (d[r].squaredNorm() - w(v[r + 1]) + w(v[0])) / 2;
  }
  const Vector3d c12 = d[1].cross(d[2]), c20 = d[2].cross(d[0]), c01 = d[0].cross(d[1]);
  const double det = d[0].dot(c12);
  Vector3d x;
  if (std::abs(det) > 1e-12 * d[0].norm() * d[1].norm() * d[2].norm()) {
    x = (b[0] * c12 + b[1] * c20 + b[2] * c01) / det;
  } else {  // too flat for doubles: solve it exactly
    Vector3d c;
    const Eigen::Vector4d weights(w(v[0]), w(v[1]), w(v[2]), w(v[3]));
    if (!exact_orthocentre(p0, p.row(v[1]).transpose(), p.row(v[2]).transpose(),
                           p.row(v[3]).transpose(), weights, c))
      return false;
    x = c - p0;
  }
  // q outside violates the tet iff |c - q|^2 - w_q < r^2 = |c - p0|^2 - w0, and w_q <= max_weight.
  const Vector3d c = p0 + x;
  const double r2 = x.squaredNorm() - w(v[0]);
  Box grown = need;
  if (sphere_inside(c, r2 + max_weight, box, margin, grown)) return true;
  // The sphere leaves the box: the samples outside it that it can reach are all in the shell.
  if (shell && std::isfinite(r2) && c.allFinite()) {
    const double reach = std::sqrt(std::max(r2 + max_weight, 0.0)) + margin;
    if (shell->outer().depth(c) > reach && shell->conflict_free(c, r2, reach, margin)) return true;
  }
  need = grown;
  return false;
}

bool power_circle_inside(const PointMatrix& p, const Eigen::VectorXd& values, const int* v,
                         const Box& box, double max_weight, double margin, Box& need) {
  auto w = [&](int i) { return values[i] * values[i]; };
  const Vector3d p0 = p.row(v[0]).transpose();
  const Vector3d d1 = p.row(v[1]).transpose() - p0, d2 = p.row(v[2]).transpose() - p0;
  // x = s d1 + t d2 with 2 d_r . x = |d_r|^2 - w_r + w_0 (r = 1, 2).
  const double a11 = d1.dot(d1), a12 = d1.dot(d2), a22 = d2.dot(d2);
  const double b1 = (a11 - w(v[1]) + w(v[0])) / 2, b2 = (a22 - w(v[2]) + w(v[0])) / 2;
  const double det = a11 * a22 - a12 * a12;
  if (!(det > 1e-12 * a11 * a22)) return false;  // a sliver triangle: not certified here
  const Vector3d x = ((b1 * a22 - b2 * a12) * d1 + (b2 * a11 - b1 * a12) * d2) / det;
  return sphere_inside(p0 + x, x.squaredNorm() - w(v[0]) + max_weight, box, margin, need);
}

bool hull_facets_global(const Samples& ls, const Triangulation& tri, int r,
                        const std::vector<Vector3d>& hull, double max_weight, double margin,
                        const Box& box, Box& need) {
  struct Facet {
    std::array<int, 3> v;
    int opposite;
  };
  std::vector<Facet> facets;
  for (int o = tri.incident_offsets[std::size_t(r)]; o < tri.incident_offsets[std::size_t(r) + 1];
       ++o) {
    const auto tet = tri.tets.row(tri.incident_tets[std::size_t(o)]);
    for (int j = 0; j < 4; ++j) {
      if (tet[j] == r) continue;
      Facet f{{}, tet[j]};
      for (int i = 0, n = 0; i < 4; ++i)
        if (i != j) f.v[std::size_t(n++)] = tet[i];
      std::sort(f.v.begin(), f.v.end());
      facets.push_back(f);
    }
  }
  std::sort(facets.begin(), facets.end(), [](const Facet& a, const Facet& b) { return a.v < b.v; });
  auto at = [&](int i) -> Vector3d { return ls.points.row(i).transpose(); };
  bool ok = true;
  for (std::size_t i = 0, j; i < facets.size(); i = j) {
    for (j = i + 1; j < facets.size() && facets[j].v == facets[i].v;) ++j;
    if (j > i + 1) continue;  // shared by two finite tets: not on the hull
    const Facet& f = facets[i];
    switch (classify_hull_facet(at(f.v[0]), at(f.v[1]), at(f.v[2]), at(f.opposite), hull)) {
      case HullFacet::Global:
        break;
      case HullFacet::InGlobalFace:
        ok &= power_circle_inside(ls.points, ls.values, f.v.data(), box, max_weight, margin, need);
        break;
      case HullFacet::NotGlobal:
        return false;
    }
  }
  return ok;
}

}  // namespace sdfcontour
