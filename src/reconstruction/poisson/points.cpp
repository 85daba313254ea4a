#include "reconstruction/poisson/points.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "reconstruction/poisson/bspline.h"
#include "sdfcontour/pipeline/option_ranges.h"

namespace sdfcontour::poisson {

namespace {

// The finest level refines the whole surface: a closed surface spanning the points' domain crosses
// about 6 * 4^depth of its cells (measured: depth 10 gives 5.9 million triangles, depth 12 97
// million from 33k points), each costing ~48 bytes by the end. Refused when that passes half the
// machine's memory: a run that cannot finish should fail at once.
void require_affordable_depth(int depth) {
  const double triangles = 6.0 * std::pow(4.0, depth), bytes = 48.0 * triangles;
  const double memory = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGE_SIZE));
  if (memory > 0 && bytes > 0.5 * memory) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "poisson: depth %d would make about %.0f million triangles (%.1f GiB), more than "
                  "half of this machine's %.1f GiB; use a smaller depth",
                  depth, triangles / 1e6, bytes / double(1 << 30), memory / double(1 << 30));
    throw Error(text);
  }
}

}  // namespace

void validate(const OrientedPoints& input, const PoissonOptions& o) {
  const Eigen::Index n = input.points.rows();
  if (n == 0) throw Error("poisson: no points to reconstruct from");
  if (input.normals.rows() != n) throw Error("poisson: points and normals differ in count");
  require_in_range("--depth", o.depth, "poisson: depth");
  require_in_range("--full-depth", o.full_depth, "poisson: full depth");
  require_affordable_depth(o.depth);
  if (o.degree != 1 && o.degree != 2) throw Error("poisson: degree must be 1 or 2");
  if (o.full_depth < 1) throw Error("poisson: full depth must be at least 1");
  if (o.refine_dilation < 1 || o.refine_dilation > 4)
    throw Error("poisson: the refinement's dilation must be between 1 and 4 cells");
  if (!(o.scale >= 1.0) || !std::isfinite(o.scale))
    throw Error("poisson: scale must be at least 1");
  if (!(o.samples_per_node > 0) || !std::isfinite(o.samples_per_node))
    throw Error("poisson: samples per node must be positive");
  if (!(o.point_weight >= 0) || !std::isfinite(o.point_weight))
    throw Error("poisson: the point weight must be >= 0");
  for (double t : {o.solver_tolerance, o.finest_solver_tolerance})
    if (!(t > 0 && t < 1)) throw Error("poisson: solver tolerances must lie in (0, 1)");
  if (input.weights.size() != 0 && input.weights.size() != n)
    throw Error("poisson: points and weights differ in count");
  for (Eigen::Index i = 0; i < input.weights.size(); ++i)
    if (!(input.weights[i] > 0 && input.weights[i] <= 1))
      throw Error("poisson: point " + std::to_string(i) + " has a weight outside (0, 1]");
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!input.points.row(i).allFinite() || !input.normals.row(i).allFinite())
      throw Error("poisson: point " + std::to_string(i) +
                  " has a NaN or infinite coordinate or normal");
    if (!(input.normals.row(i).norm() > 0))
      throw Error("poisson: point " + std::to_string(i) + " has a zero normal");
  }
  if (const std::string why = poisson_no_surface(input.points); !why.empty())
    throw Error("poisson: " + why);
}

UnitPoints to_unit_cube(const OrientedPoints& input, double scale) {
  UnitPoints unit;
  const Eigen::Vector3d lo = input.points.colwise().minCoeff(),
                        hi = input.points.colwise().maxCoeff();
  unit.centre = 0.5 * (lo + hi);
  unit.size = (hi - lo).maxCoeff() * scale;
  if (!(unit.size > 0)) unit.size = 1.0;
  unit.points.resize(std::size_t(input.points.rows()));
  for (Eigen::Index i = 0; i < input.points.rows(); ++i) {
    auto& s = unit.points[std::size_t(i)];
    s.p = unit.to_unit(input.points.row(i).transpose());
    s.n = input.normals.row(i).transpose().normalized();
    if (input.weights.size()) s.weight = input.weights[i];
  }
  return unit;
}

MortonRuns::MortonRuns(const std::vector<UnitPoint>& points, int depth)
    : depth_(depth), order_(points.size()) {
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t s) {
    order_[s] = {morton(cell_of(points[s].p, 1L << depth)), std::uint32_t(s)};
  });
  tbb::parallel_sort(order_.begin(), order_.end());
}

}  // namespace sdfcontour::poisson

namespace sdfcontour {

std::string poisson_no_surface(const PointMatrix& points) {
  const Eigen::Index n = points.rows();
  if (n < 4) return std::to_string(n) + " points make no surface (at least 4)";
  const Eigen::RowVector3d extent = points.colwise().maxCoeff() - points.colwise().minCoeff();
  if (!(extent.maxCoeff() > 0)) return "all the points lie at one place";
  return "";
}

}  // namespace sdfcontour
