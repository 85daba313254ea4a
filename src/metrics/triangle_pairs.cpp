// Whether two triangles of a mesh meet other than in what they share: floating-point certificates
// first (a separating axis, sectors apart around a shared vertex), CGAL's exact predicates where
// those leave it open.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <array>
#include <cmath>

#include "metrics/clear_turns.h"
#include "sdfcontour/metrics/self_intersections.h"

namespace sdfcontour {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

Point point(const Eigen::Vector3d& x) {
  return Point(x[0], x[1], x[2]);
}

using detail::kClear;

// Whether two triangles that share the vertex s[os] = t[ot] clearly meet there alone: seen along
// their mean normal, both keep their orientation and their corners' sectors around the vertex
// lie apart with room to spare. A triangle's points then project one to one, so the two meet in
// the shared vertex only. False where it is not clear (exact predicates decide those): a flat
// region's pairs, coplanar to the last bit, need no exact arithmetic when their sectors are apart.
bool clearly_apart_around(const std::array<Eigen::Vector3d, 3>& s, int os,
                          const std::array<Eigen::Vector3d, 3>& t, int ot) {
  const Eigen::Vector3d o = s[std::size_t(os)];
  const Eigen::Vector3d a1 = s[std::size_t(os + 1) % 3] - o, a2 = s[std::size_t(os + 2) % 3] - o;
  const Eigen::Vector3d b1 = t[std::size_t(ot + 1) % 3] - o, b2 = t[std::size_t(ot + 2) % 3] - o;
  const Eigen::Vector3d ns = a1.cross(a2), nt = b1.cross(b2);
  const double ls = ns.norm(), lt = nt.norm();
  if (!(ls > 0) || !(lt > 0)) return false;
  const Eigen::Vector3d m = ns / ls + nt / lt;
  const double lm = m.norm();
  if (!(lm > 1)) return false;  // the normals more than 120 degrees apart
  const Eigen::Vector3d n = m / lm;
  auto clearly = [&](const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
    return detail::clearly_turns(n, x, y);
  };
  // Both counter-clockwise about n, and going round: a1, a2, b1, b2, each turn under half.
  return clearly(a1, a2) && clearly(b1, b2) && clearly(a2, b1) && clearly(b2, a1);
}

// Whether two triangles are clearly apart: along one of their normals, or one of the directions
// in a triangle's plane across an edge, their corners' spans leave a gap well beyond rounding (a
// separating axis is proof for convex sets). Coplanar neighbours, which no floating-point filter
// decides, are mostly settled so.
bool clearly_separated(const std::array<Eigen::Vector3d, 3>& s,
                       const std::array<Eigen::Vector3d, 3>& t) {
  const Eigen::Vector3d ns = (s[1] - s[0]).cross(s[2] - s[0]);
  const Eigen::Vector3d nt = (t[1] - t[0]).cross(t[2] - t[0]);
  double scale = 0;
  for (const auto* x : {&s, &t})
    for (const Eigen::Vector3d& p : *x) scale = std::max(scale, (p - s[0]).norm());
  auto apart_along = [&](const Eigen::Vector3d& axis) {
    const double length = axis.norm();
    if (!(length > 0)) return false;
    double lo_s = INFINITY, hi_s = -INFINITY, lo_t = INFINITY, hi_t = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      const double ds = axis.dot(s[std::size_t(k)] - s[0]), dt = axis.dot(t[std::size_t(k)] - s[0]);
      lo_s = std::min(lo_s, ds), hi_s = std::max(hi_s, ds);
      lo_t = std::min(lo_t, dt), hi_t = std::max(hi_t, dt);
    }
    const double gap = kClear * length * scale;
    return lo_t > hi_s + gap || lo_s > hi_t + gap;
  };
  if (apart_along(ns) || apart_along(nt)) return true;
  for (int k = 0; k < 3; ++k)
    if (apart_along(ns.cross(s[std::size_t(k + 1) % 3] - s[std::size_t(k)])) ||
        apart_along(nt.cross(t[std::size_t(k + 1) % 3] - t[std::size_t(k)])))
      return true;
  return false;
}

}  // namespace

namespace detail {

bool triangles_cross(const std::array<Eigen::Vector3d, 3>& s_at, const std::array<int, 3>& S,
                     const std::array<Eigen::Vector3d, 3>& t_at, const std::array<int, 3>& T) {
  int shared_s = -1, shared_t = -1, shared = 0;
  bool in_t[3] = {false, false, false};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (S[std::size_t(i)] == T[std::size_t(j)])
        shared_s = i, shared_t = j, ++shared, in_t[i] = true;
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 2) {
    // A shared edge: they overlap iff they fold onto each other (coplanar, the opposite vertices
    // on the same side of the edge); subdividing such a fold makes triangles that cross.
    const int a = !in_t[0] ? 0 : !in_t[1] ? 1 : 2;
    int b = 0;
    while (T[std::size_t(b)] == S[0] || T[std::size_t(b)] == S[1] || T[std::size_t(b)] == S[2]) ++b;
    const Point u = point(s_at[std::size_t(a + 1) % 3]), v = point(s_at[std::size_t(a + 2) % 3]),
                p = point(s_at[std::size_t(a)]), q = point(t_at[std::size_t(b)]);
    return !CGAL::collinear(u, v, p) && CGAL::coplanar(u, v, p, q) &&
           CGAL::coplanar_orientation(u, v, p, q) == CGAL::POSITIVE;
  }
  if (shared == 0 ? clearly_separated(s_at, t_at)
                  : clearly_apart_around(s_at, shared_s, t_at, shared_t))
    return false;
  const K::Triangle_3 a(point(s_at[0]), point(s_at[1]), point(s_at[2])),
      b(point(t_at[0]), point(t_at[1]), point(t_at[2]));
  if (shared == 0) return CGAL::do_intersect(a, b);
  // One shared vertex: they cross elsewhere iff an edge opposite it cuts the other triangle.
  const K::Segment_3 opposite_s(point(s_at[std::size_t(shared_s + 1) % 3]),
                                point(s_at[std::size_t(shared_s + 2) % 3])),
      opposite_t(point(t_at[std::size_t(shared_t + 1) % 3]),
                 point(t_at[std::size_t(shared_t + 2) % 3]));
  // An edge with both ends strictly on one side of the other's plane cuts neither triangle, and
  // then the two meet in the shared vertex alone (most neighbours on a mesh: two orientations
  // instead of two segment-triangle tests).
  auto apart = [](const K::Triangle_3& x, const K::Segment_3& e) {
    const CGAL::Orientation side = CGAL::orientation(x[0], x[1], x[2], e.source());
    return side != CGAL::COPLANAR && CGAL::orientation(x[0], x[1], x[2], e.target()) == side;
  };
  if (apart(a, opposite_t) || apart(b, opposite_s)) return false;
  return CGAL::do_intersect(opposite_s, b) || CGAL::do_intersect(opposite_t, a);
}

bool collinear_corners(const std::array<Eigen::Vector3d, 3>& c) {
  return CGAL::collinear(point(c[0]), point(c[1]), point(c[2]));
}

}  // namespace detail

}  // namespace sdfcontour
