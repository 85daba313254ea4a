// contour()'s local reconstruction stage: GCP's or GTCP's contact points to a mesh on the grid's
// cells, subdivided and projected onto the contact points where they fit a smooth surface.
#include "../../pipeline_stages.h"
#include "sdfcontour/subdivision.h"

namespace sdfcontour::detail {

void reconstruct_locally(const GridView& grid, const ReconstructionInputs& inputs,
                         const ContourOptions& options, ContourResult& result, Stages& stages) {
  const ContactPoints& cp = *result.contact_points;
  LocalReconstructionStats stats;
  Mesh mesh = stages.run(
      "local", "local reconstruction from " + std::to_string(cp.size()) + " contact points", [&] {
        return local_reconstruction(grid, cp.points, cp.normals, options.local, &stats,
                                    inputs.contact_depths);
      });
  const int levels =
      options.subdivisions >= 0
          ? options.subdivisions
          : auto_subdivisions(double(*std::max_element(grid.dims.begin(), grid.dims.end())));
  if (levels > 0)
    mesh = stages.run("subdivision", "midpoint subdivision", [&] {
      for (int l = 0; l < levels; ++l) mesh = midpoint_subdivision(mesh);
      return std::move(mesh);
    });
  result.mesh = std::move(mesh);
  refine_stage(inputs, options, result, stages);
  result.local = stats;
  result.reconstruction = Reconstruction::Local;
}

}  // namespace sdfcontour::detail
