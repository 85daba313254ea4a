// contour() of a grid read a block at a time (a .vdb level set), and its mesh placed in the
// world.
#include <cmath>
#include <limits>

#include "pipeline/pipeline_stages.h"
#include "sdfcontour/extraction/brick_marching.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

// A grid read a block at a time (a .vdb level set): marching cubes or GCP's local reconstruction
// brick by brick, the values taken as distances (a level set's are), nothing measured of the
// whole grid; its own truncation (the background) unless the options give one.
ContourResult contour_blocked_grid(const BlockedGridInput& input, const ContourOptions& given) {
  const BlockedGrid& grid = input.grid;
  validate_grid_geometry(grid);
  ContourOptions options = given;
  if (options.band.truncation_mode == TruncationMode::Auto && input.truncation > 0) {
    options.band.truncation_mode = TruncationMode::Given;
    options.band.truncation = input.truncation;
  }
  const bool mc = options.method == Method::Mc && !options.want_points;
  if (!options.want_mesh ||
      (!mc && (options.method != Method::Gcp || options.reconstruction == Reconstruction::Poisson ||
               !local_gradients(options.gradient_source) || !std::isfinite(options.band.band))))
    throw Error(
        "a grid read block by block (a .vdb level set) takes marching cubes or GCP's local "
        "reconstruction to a mesh, with regular or lattice gradients and a finite band: read "
        "it as scattered samples for the rest");
  ContourResult result;
  const double samples = double(grid.dims[0]) * grid.dims[1] * grid.dims[2];
  result.samples = int(std::min(samples, double(std::numeric_limits<int>::max())));
  Stages stages(result, options);
  if (mc) {
    result.mesh = stages.run("marching", "marching cubes brick by brick",
                             [&] { return marching_cubes(grid, kLocalBrick); });
    if (result.mesh->triangles.rows() == 0)
      throw Error("no surface: the values have no sign change inside the grid");
    return result;
  }
  detail::reconstruct_in_bricks(grid, options.band, options, result, stages);
  return result;
}

// The outputs of a grid contoured in its own frame, placed in the world (a rigid motion: the
// distances, and so the mesh, are the same).
void place_in_world(const Eigen::Affine3d& world_from_grid, ContourResult& result) {
  auto place = [&](PointMatrix& points, bool directions) {
    for (Eigen::Index r = 0; r < points.rows(); ++r) {
      const Eigen::Vector3d p = points.row(r).transpose();
      points.row(r) = (directions ? Eigen::Vector3d(world_from_grid.linear() * p)
                                  : Eigen::Vector3d(world_from_grid * p))
                          .transpose();
    }
  };
  if (result.mesh) place(result.mesh->vertices, false);
  if (result.contact_points) {
    place(result.contact_points->points, false);
    place(result.contact_points->normals, true);
  }
}

}  // namespace sdfcontour::detail
