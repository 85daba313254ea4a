// The grid at twice the resolution with the thin parts' signs (thin_parts.h).
#include "reconstruction/local/thin_parts.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <type_traits>
#include <utility>

#include "reconstruction/point_cubes.h"
#include "sdfcontour/reconstruction/zero_set_refinement.h"

namespace sdfcontour::detail {

namespace {

// How far (in spacings) behind or in front of every near tangent plane a point must lie for the
// planes to decide its side: above the rounding of exact contact points.
constexpr double kPlaneHair = 1e-9;

// Normals of the contact points within a spacing this far apart (radians) mark a crease, where the
// field kinks between the samples and the interpolants may put a point on the wrong side.
constexpr double kCreaseAngle = 1.0;

// A contact point near a point of the finer grid: its squared distance and its row.
struct Near {
  double d2;
  int row;
};
using NearList = std::vector<Near>;

// The rows of the contact points within `radius` of x, the nearest first (ties by position, so
// that the rows' order does not matter); the rest in any order (only the nearest is read alone).
// `rows` is PointCubes::collect_within's buffer.
void points_near(const Eigen::Vector3d& x, double radius, const PointCubes* cubes,
                 const PointMatrix& points, std::vector<int>& rows, NearList& near) {
  near.clear();
  if (!cubes) return;
  const int count = cubes->collect_within(points, x, radius * radius, 1, rows);
  for (int e = 0; e < count; ++e) {
    const int r = rows[std::size_t(e)];
    near.push_back({(x - points.row(r).transpose()).squaredNorm(), r});
  }
  auto closer = [&](const Near& a, const Near& b) {
    if (a.d2 != b.d2) return a.d2 < b.d2;
    for (int d = 0; d < 3; ++d)
      if (points(a.row, d) != points(b.row, d)) return points(a.row, d) < points(b.row, d);
    return a.row < b.row;
  };
  if (!near.empty())
    std::iter_swap(near.begin(), std::min_element(near.begin(), near.end(), closer));
}

// Whether the contact points `near` x put it in a thin part of the side opposite to `side` (+1:
// outside, -1: inside): two tangent planes with x within `slack` of the slab between them, facing
// away from each other (side +1: a sheet of inside) or toward each other (side -1: a gap), and
// no plane with x more than `slack` in front of it (seen from `side`).
bool in_thin_part(const Eigen::Vector3d& x, int side, const NearList& near,
                  const PointMatrix& points, const PointMatrix& normals, double slack) {
  // Normals as seen from the side x is on: a part of the other side is then a slab behind two
  // planes that face away from each other.
  for (const auto& [d2, r] : near)
    if (side * normals.row(r).dot(x.transpose() - points.row(r)) > slack) return false;
  for (std::size_t a = 0; a < near.size(); ++a) {
    const Eigen::Vector3d ca = points.row(near[a].row).transpose();
    const Eigen::Vector3d na = side * normals.row(near[a].row).transpose();
    for (std::size_t b = a + 1; b < near.size(); ++b) {
      const Eigen::Vector3d nb = side * normals.row(near[b].row).transpose();
      if (na.dot(nb) > -0.5) continue;
      const Eigen::Vector3d cb = points.row(near[b].row).transpose();
      // Each point behind the other's plane: the slab between them is the other side's.
      if (na.dot(cb - ca) <= 0 && nb.dot(ca - cb) <= 0) return true;
    }
  }
  return false;
}

// Whether two of the contact points `near` have normals more than kCreaseAngle apart.
bool at_crease(const NearList& near, const PointMatrix& normals) {
  const double cos_crease = std::cos(kCreaseAngle);
  for (std::size_t a = 0; a < near.size(); ++a)
    for (std::size_t b = a + 1; b < near.size(); ++b)
      if (normals.row(near[a].row).dot(normals.row(near[b].row)) < cos_crease) return true;
  return false;
}

// Whether the block's point `at` lies on a side of its whole grid.
bool on_side(const GridView& block, const std::array<int, 3>& at) {
  const std::array<int, 3> whole = block.whole_dims();
  for (int a = 0; a < 3; ++a)
    if (block.first[a] + at[a] == 0 || block.first[a] + at[a] == whole[a] - 1) return true;
  return false;
}

// The value of the finer grid's point `at`, between samples near the surface, whose mean (the
// trilinear interpolant) is `value` (thin_parts.h's 1-3); a thin part's point joins `thin`.
double value_near_surface(const GridView& block, const GridView& fine, const std::array<int, 3>& at,
                          double value, const PointCubes* cubes, const PointMatrix& points,
                          const PointMatrix& normals, double value_scale, double truncation,
                          std::vector<int>& rows, NearList& near,
                          std::vector<std::array<int, 3>>& thin) {
  const double h = block.spacing().maxCoeff();
  // The samples x lies between, in the order of their offsets' bits (i the lowest).
  std::array<std::array<int, 3>, 8> parents;
  std::array<double, 8> values;
  int count = 0;
  for (int dk = 0; dk <= (at[2] & 1); ++dk)
    for (int dj = 0; dj <= (at[1] & 1); ++dj)
      for (int di = 0; di <= (at[0] & 1); ++di) {
        const std::array<int, 3> p{at[0] / 2 + di, at[1] / 2 + dj, at[2] / 2 + dk};
        parents[std::size_t(count)] = p;
        values[std::size_t(count++)] = block.value(block.index(p[0], p[1], p[2]));
      }
  const Eigen::Vector3d x = fine.point(at[0], at[1], at[2]);
  points_near(x, h, cubes ? &*cubes : nullptr, points, rows, near);
  // The tricubic interpolant is closer to a distance's zero set than the mean, where
  // its stencil lies in the block and holds no truncated value; where the two disagree
  // on the side (a surface within a hair of x, or a kink of the field in the stencil: a
  // box's edge), the nearest contact point's tangent plane decides.
  double cubic;
  Eigen::Vector3d gradient;
  if (tricubic_value(block, x, truncation, cubic, gradient)) {
    if ((cubic < 0) == (value < 0) || near.empty())
      value = cubic;
    else
      value = normals.row(near[0].row).dot(x.transpose() - points.row(near[0].row)) / value_scale;
  }
  // At a crease, behind every tangent plane of the contact points within a spacing, or
  // in front of every one, x is on that side whatever the interpolants say: next to a
  // box's convex edge both put the points just inside it outside (the cube at 128^3:
  // false crossings up to 0.15 h inside its edges, their vertices clamped to the cells'
  // corners). (Where the surface is smooth, a curved patch's planes can all pass on one
  // side of x when its points are sparse: blub 64^3's L-infinity 1.6x.)
  if (!near.empty()) {
    double least = INFINITY, most = -INFINITY;
    for (const auto& [d2, r] : near) {
      const double s = normals.row(r).dot(x.transpose() - points.row(r));
      least = std::min(least, s);
      most = std::max(most, s);
    }
    const double hair = kPlaneHair * h;
    const double planes = value >= 0 && most < -hair ? most : value < 0 && least > hair ? least : 0;
    if (planes != 0 && at_crease(near, normals)) value = planes / value_scale;
  }
  // A point in a sample's ball (radius |value|, which holds no surface) is on its side:
  // an interpolant can miss that where the surface passes within a hair of x (next to
  // a box's edge, where the field is not smooth), and the narrow cells' vertices then
  // lie off their cells.
  double certain = 0;
  for (int c = 0; c < count; ++c) {
    const double v = values[std::size_t(c)];
    const auto& p = parents[std::size_t(c)];
    const double margin = std::abs(v) - (x - block.point(p[0], p[1], p[2])).norm() / value_scale;
    if (margin > std::abs(certain)) certain = v < 0 ? -margin : margin;
  }
  if (certain != 0 && (certain < 0) != (value < 0)) value = certain;
  const int side = value < 0 ? -1 : 1;
  // (Not on the grid's sides: a part marked there would leave the mesh open.)
  if (!on_side(fine, at) && in_thin_part(x, side, near, points, normals, h / 4)) {
    value = -side * h / 8 / value_scale;
    thin.push_back({fine.first[0] + at[0], fine.first[1] + at[1], fine.first[2] + at[2]});
  }
  return value;
}

}  // namespace

RefinedGrid refine_for_thin_parts(const GridView& block, const PointMatrix& points,
                                  const PointMatrix& normals, double value_scale,
                                  double truncation) {
  RefinedGrid out;
  GridView& fine = out.view;
  static_cast<GridGeometry&>(fine) = block;
  const std::array<int, 3> whole = block.whole_dims();
  for (int a = 0; a < 3; ++a) {
    fine.dims[a] = 2 * block.dims[a] - 1;
    fine.first[a] = 2 * block.first[a];
    fine.whole[a] = block.whole[0] > 0 ? 2 * whole[a] - 1 : 0;
  }
  out.values.resize(fine.size());
  fine.data = out.values.data();
  fine.type = ScalarType::Float64;
  fine.drop_pages = nullptr;
  const double h = block.spacing().maxCoeff();
  // (Cubes a spacing wide: the points within a spacing of x lie in the 27 around it.)
  const std::optional<PointCubes> cubes =
      points.rows() > 0 ? std::optional<PointCubes>(std::in_place, points, h) : std::nullopt;
  std::vector<std::vector<std::array<int, 3>>> thin(std::size_t(fine.dims[0]));
  tbb::parallel_for(0, fine.dims[0], [&](int I) {
    std::vector<int> near_rows;
    NearList near;
    block.visit([&](const auto* f) {
      using T = std::remove_const_t<std::remove_pointer_t<decltype(f)>>;
      for (int J = 0; J < fine.dims[1]; ++J) {
        // The rows of samples that the row's points lie between: both neighbours on each axis
        // where the index is odd, in the order of their offsets' bits (i the lowest), the same
        // order as value_near_surface's.
        std::array<const T*, 4> rows;
        int row_count = 0;
        for (int dj = 0; dj <= (J & 1); ++dj)
          for (int di = 0; di <= (I & 1); ++di)
            rows[std::size_t(row_count++)] = f + block.index(I / 2 + di, J / 2 + dj, 0);
        double* const out_row = out.values.data() + fine.index(I, J, 0);
        for (int K = 0; K < fine.dims[2]; ++K) {
          double sum = 0, nearest = INFINITY;
          for (int dk = 0; dk <= (K & 1); ++dk)
            for (int r = 0; r < row_count; ++r) {
              const double v = double(rows[std::size_t(r)][K / 2 + dk]);
              sum += v;
              nearest = std::min(nearest, std::abs(v) * value_scale);
            }
          const int count = row_count * (1 + (K & 1));
          double value = sum / count;
          // Between samples near the surface: the interpolant there, and a thin part may pass
          // between them.
          if (count > 1 && nearest < h)
            value = value_near_surface(block, fine, {I, J, K}, value, cubes ? &*cubes : nullptr,
                                       points, normals, value_scale, truncation, near_rows, near,
                                       thin[std::size_t(I)]);
          out_row[K] = value;
        }
      }
    });
  });
  for (const auto& t : thin) out.thin_points.insert(out.thin_points.end(), t.begin(), t.end());
  return out;
}

}  // namespace sdfcontour::detail
