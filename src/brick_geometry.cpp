#include "brick_geometry.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>
#include <tbb/parallel_for.h>

#include <iterator>

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
    std::vector<Point> own;
    own.reserve(buckets[b].size());
    for (int r : buckets[b]) own.push_back(Point(points(r, 0), points(r, 1), points(r, 2)));
    per_bucket[b] = extreme_points(own);
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

}  // namespace sdfcontour
