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
//  quadratic_basis.h, quadratic_system.h   the same with degree-2 elements
//  indicator.h    chi anywhere; extraction.h  its iso-surface, watertight
//  sign_constraints.h  optionally, chi corrected to keep samples of known side on their side
#include <chrono>
#include <cmath>
#include <functional>

#include "pipeline/enum_names.h"
#include "reconstruction/poisson/cascade.h"
#include "reconstruction/poisson/density.h"
#include "reconstruction/poisson/deterministic_sum.h"
#include "reconstruction/poisson/extraction.h"
#include "reconstruction/poisson/indicator.h"
#include "reconstruction/poisson/normal_field.h"
#include "reconstruction/poisson/octree.h"
#include "reconstruction/poisson/points.h"
#include "reconstruction/poisson/sign_constraints.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/reconstruction/poisson.h"

namespace sdfcontour {

namespace {

// The pieces of a closed triangle mesh wider than `min_extent` along some axis: how many, and
// twice their Euler characteristic in all (2V - F). Smaller pieces are the extraction's bubbles.
std::pair<long, long> significant_topology(const Mesh& m, double min_extent) {
  const std::vector<int> label = component_labels(m);
  const std::vector<Eigen::AlignedBox3d> box = component_boxes(m, label);
  std::vector<long> twice_euler(box.size(), 0);
  for (const int l : label)
    if (l >= 0) twice_euler[std::size_t(l)] += 2;
  for (Eigen::Index t = 0; t < m.triangles.rows(); ++t)
    twice_euler[std::size_t(label[std::size_t(m.triangles(t, 0))])] -= 1;
  std::pair<long, long> r{0, 0};
  for (std::size_t c = 0; c < box.size(); ++c)
    if (box[c].sizes().maxCoeff() >= min_extent) ++r.first, r.second += twice_euler[c];
  return r;
}

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
  return poisson_reconstruct(input, o, SignedSamples{}, SignConstraintOptions{});
}

namespace {

// The reconstruction from the points in the unit cube that `unit_points` makes (after checking
// the input); see poisson_reconstruct.
PoissonResult reconstruct(const std::function<poisson::UnitPoints()>& unit_points,
                          const PoissonOptions& o, const SignedSamples& sides,
                          const SignConstraintOptions& sign_options) {
  using namespace poisson;
  PoissonResult result;
  StageTimer stage(result, o);
  stage.start("setup");
  const int D = o.depth, d_min = std::min(o.full_depth, o.depth);
  UnitPoints unit = unit_points();

  stage.start("density");
  const MortonRuns runs(unit.points, D);
  const SamplingDensity density(unit.points, runs, std::max(1, D - 2));
  const double area_per_point =
      assign_areas_and_depths(unit.points, density, o.samples_per_node, d_min, D, o.degree == 2);

  stage.start("octree");
  Octree tree = build_octree(unit.points, runs, d_min, D, o.refine_dilation, o.cancel);

  stage.start("splatting");
  NormalField field = splat_normals(tree, unit.points, runs, o.cancel, o.degree == 1);

  stage.start("solve");
  CascadeResult solution =
      o.degree == 2
          ? solve_coarse_to_fine_quadratic(tree, field, unit.points, runs, area_per_point, o)
          : solve_coarse_to_fine(tree, field, unit.points, runs, area_per_point, o);
  result.levels = std::move(solution.levels);
  result.boundary_fallback = solution.boundary_fallback;
  Indicator chi(tree, std::move(solution.values));

  stage.start("iso-value");
  // The weighted mean of chi at the points (with unit weights, the plain mean).
  const auto& pts = unit.points;
  result.iso_value =
      !std::isnan(solution.iso_value)
          ? solution.iso_value
          : deterministic_sum(pts.size(), [&](std::size_t s) {
              return pts[s].weight * chi.at(pts[s].p);
            }) / deterministic_sum(pts.size(), [&](std::size_t s) { return pts[s].weight; });

  if (sides.points.rows() > 0) {
    if (sides.values.size() != sides.points.rows())
      throw Error("poisson: signed samples and values differ in count");
    stage.start("sign constraints");
    std::vector<std::vector<double>> solved;
    for (int d = 0; d <= tree.finest; ++d) solved.push_back(chi.values(d));
    const poisson::SignCorrection c =
        poisson::enforce_signs(chi, result.iso_value, sides, unit, sign_options);
    result.sign_violations = c.violations;
    result.sign_violations_left = c.violations_left;
    stage.start("extraction");
    // Degree 2: chi along the edges is the solved chi plus the corrections, which are trilinear
    // (node values' changes).
    const Indicator unconstrained_chi(tree, std::move(solved));
    std::function<double(const Eigen::Vector3d&)> along_edges;
    if (solution.evaluate)
      along_edges = [&](const Eigen::Vector3d& p) {
        return solution.evaluate(p) + (chi.at(p) - unconstrained_chi.at(p));
      };
    result.mesh = extract_iso_surface(chi, result.iso_value, unit, o.cancel, along_edges);
    // The corrections move the surface by a fraction of a sample spacing; where they would change
    // its topology (a handle across a crease, a piece; bubbles smaller than the correction's
    // radius aside), the solved chi's surface is kept. Without a correction there is nothing to
    // compare.
    if (c.sweeps > 0) {
      Mesh unconstrained = extract_iso_surface(unconstrained_chi, result.iso_value, unit, o.cancel,
                                               solution.evaluate);
      if (significant_topology(result.mesh, sign_options.radius) !=
          significant_topology(unconstrained, sign_options.radius)) {
        result.mesh = std::move(unconstrained);
        result.sign_constraints_dropped = true;
      }
    }
  } else {
    stage.start("extraction");
    result.mesh = extract_iso_surface(chi, result.iso_value, unit, o.cancel, solution.evaluate);
  }

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

}  // namespace

PoissonResult poisson_reconstruct(const OrientedPoints& input, const PoissonOptions& o,
                                  const SignedSamples& sides,
                                  const SignConstraintOptions& sign_options) {
  return reconstruct(
      [&] {
        poisson::validate(input, o);
        return poisson::to_unit_cube(input, o.scale);
      },
      o, sides, sign_options);
}

PoissonResult poisson_reconstruct(OrientedPoints&& input, const PoissonOptions& o,
                                  const SignedSamples& sides,
                                  const SignConstraintOptions& sign_options) {
  return reconstruct(
      [&] {
        poisson::validate(input, o);
        poisson::UnitPoints unit = poisson::to_unit_cube(input, o.scale);
        input = OrientedPoints();
        return unit;
      },
      o, sides, sign_options);
}

}  // namespace sdfcontour
