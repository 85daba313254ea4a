// Screened Poisson reconstruction on an adaptive octree, written from the method of Kazhdan,
// Bolitho & Hoppe (2006) and Kazhdan & Hoppe (2013). The stages, each in its own unit:
//
//  points.h       check the input, map it into the unit cube, sort it in Morton order
//  density.h      points per unit area around each point: its weight and its splat depth
//  octree.h       complete to the full depth, then refined around points that want the depth
//  normal_field.h the normals splatted with quadratic B-splines, and their divergence
//  system.h       one depth's screened system (stiffness + screening at the points)
//  conjugate_gradients.h   the solve at one depth, returning its state
//  cascade.h      coarse to fine, each depth starting from the coarser one; boundary fallback
//  indicator.h    chi anywhere; extraction.h  its iso-surface, watertight
#include <chrono>

#include "../enum_names.h"
#include "cascade.h"
#include "density.h"
#include "deterministic_sum.h"
#include "extraction.h"
#include "indicator.h"
#include "normal_field.h"
#include "octree.h"
#include "points.h"
#include "sdfcontour/poisson.h"

namespace sdfcontour {

namespace {

const detail::NameTable<PoissonBoundary> kBoundaries = {{"neumann", PoissonBoundary::Neumann},
                                                        {"dirichlet", PoissonBoundary::Dirichlet},
                                                        {"free", PoissonBoundary::Free}};

// Times named stages into PoissonResult::seconds and announces each one.
class StageTimer {
 public:
  StageTimer(PoissonResult& result, const PoissonOptions& options)
      : result_(result), progress_(options.progress), cancel_(options.cancel) {}
  // Closes the running stage (if any) and starts the next.
  void start(const std::string& name) {
    check_cancel(cancel_);
    stop();
    result_.seconds.push_back({name, 0.0});
    if (progress_) progress_("poisson: " + name);
  }
  void stop() {
    const auto now = Clock::now();
    if (!result_.seconds.empty())
      result_.seconds.back().second = std::chrono::duration<double>(now - start_).count();
    start_ = now;
  }

 private:
  using Clock = std::chrono::steady_clock;
  PoissonResult& result_;
  const std::function<void(const std::string&)>& progress_;
  const std::atomic<bool>* cancel_;
  Clock::time_point start_ = Clock::now();
};

}  // namespace

PoissonBoundary parse_poisson_boundary(const std::string& name) {
  return detail::parse_name(kBoundaries, "boundary", name);
}
std::string poisson_boundary_name(PoissonBoundary boundary) {
  return detail::name_of(kBoundaries, boundary);
}

PoissonResult poisson_reconstruct(const OrientedPoints& input, const PoissonOptions& o) {
  using namespace poisson;
  PoissonResult result;
  StageTimer stage(result, o);
  stage.start("setup");
  validate(input, o);
  const int D = o.depth, d_min = std::min(o.full_depth, o.depth);
  UnitPoints unit = to_unit_cube(input, o.scale);

  stage.start("density");
  const MortonRuns runs(unit.points, D);
  const SamplingDensity density(unit.points, runs, std::max(1, D - 2));
  const double area_per_point =
      assign_areas_and_depths(unit.points, density, o.samples_per_node, d_min, D);

  stage.start("octree");
  Octree tree = build_octree(unit.points, runs, d_min, D, o.cancel);

  stage.start("splatting");
  NormalField field = splat_normals(tree, unit.points, runs, o.cancel);

  stage.start("solve");
  CascadeResult solution = solve_coarse_to_fine(tree, field, unit.points, runs, area_per_point, o);
  result.levels = std::move(solution.levels);
  result.boundary_fallback = solution.boundary_fallback;
  const Indicator chi(tree, std::move(solution.values));

  stage.start("iso-value");
  // The weighted mean of chi at the points (with unit weights, the plain mean).
  const auto& pts = unit.points;
  result.iso_value =
      deterministic_sum(pts.size(),
                        [&](std::size_t s) { return pts[s].weight * chi.at(pts[s].p); }) /
      deterministic_sum(pts.size(), [&](std::size_t s) { return pts[s].weight; });

  stage.start("extraction");
  result.mesh = extract_iso_surface(chi, result.iso_value, unit, o.cancel);

  // Sampling density at each vertex, in points per unit area of the input's units.
  const Mesh& mesh = result.mesh;
  result.vertex_density.resize(mesh.vertices.rows());
  tbb::parallel_for(Eigen::Index(0), mesh.vertices.rows(), [&](Eigen::Index v) {
    result.vertex_density[v] =
        density.points_per_area(unit.to_unit(mesh.vertices.row(v).transpose())) /
        (unit.size * unit.size);
  });
  stage.stop();
  return result;
}

}  // namespace sdfcontour
