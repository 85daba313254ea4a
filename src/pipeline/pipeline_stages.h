// The stages of contour() (pipeline.cpp) as named units: the contact points and the triangulations
// they come from (contact_stage.cpp), and GCP's or GTCP's mesh made from them
// (reconstruction_stage.cpp). Internal to the library.
#pragma once

#include <tbb/parallel_for.h>

#include <chrono>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "pipeline/grid_source.h"
#include "sdfcontour/contact_points/triangulation.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour::detail {

// A grid of f(value) for each of `grid`'s values, stored in the grid's own precision (float32
// stays float32), owning its values.
template <class F>
GridInput mapped_grid(const GridView& grid, F f) {
  return grid.visit([&](const auto* values) {
    using T = std::remove_const_t<std::remove_pointer_t<decltype(values)>>;
    auto mapped = std::make_shared<std::vector<T>>(grid.size());
    tbb::parallel_for(std::size_t(0), mapped->size(),
                      [&](std::size_t i) { (*mapped)[i] = T(f(double(values[i]))); });
    GridInput input;
    static_cast<GridGeometry&>(input.view) = grid;
    input.view.type = grid.type;
    input.view.data = mapped->data();
    input.storage = mapped;
    return input;
  });
}

// Times each stage into the result and reports its start through the progress callback.
class Stages {
 public:
  Stages(ContourResult& result, const ContourOptions& options)
      : result_(result), options_(options) {}
  template <class F>
  auto run(const std::string& name, const std::string& message, F&& work) {
    check_cancel(options_.cancel);
    if (options_.progress) options_.progress(message);
    const auto start = std::chrono::steady_clock::now();
    auto finish = [&] {
      result_.stages.push_back(
          {name, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
    };
    if constexpr (std::is_void_v<decltype(work())>) {
      work();
      finish();
    } else {
      auto value = work();
      finish();
      return value;
    }
  }

  /// A stage's (done, total) callback onto options.progress_fraction (empty if none).
  std::function<void(long, long)> fraction(const std::string& name) const {
    if (!options_.progress_fraction) return {};
    return [this, name](long done, long total) { options_.progress_fraction(name, done, total); };
  }

 private:
  ContourResult& result_;
  const ContourOptions& options_;
};

// Where GCP's mesh cannot be trusted on the values (they do not behave as distances), a stage
// says why in ContourResult::fallback and returns; contour() then returns marching cubes' mesh
// where it may, else throws Error.

// The band's triangulations that the method's mesh still needs (marching tetrahedra), if any.
struct SampleTriangulations {
  std::optional<Triangulation> regular, delaunay;
};

// Contact points into result.contact_points (GCP's, in bricks or from one triangulation, or
// GTCP's from `shape`), naming their samples by index into `band.samples`; result.hidden and
// result.bricks as they come. Returns the triangulations made on the way.
SampleTriangulations contact_point_stage(const BandSamples& band, const AnalyticShape* shape,
                                         const ContourOptions& options, ContourResult& result,
                                         Stages& stages);

// What GCP's or GTCP's reconstruction needs once the band's samples are freed.
struct ReconstructionInputs {
  PoissonOptions poisson;   // the depth and dilation chosen
  bool auto_depth = false;  // the depth follows each cluster's extent (ContourOptions 0)
  SignedSamples sides;      // samples whose sides the indicator keeps (may be empty)
  bool project = false;     // move the vertices onto the contact points
  ContactProjectionOptions projection;  // how (the Poisson path's or the local one's)
  Eigen::VectorXd contact_depths;       // with `project`: |value| of each contact point's sample
  bool carve = false;                   // carve the mesh out of `carving_samples`' spheres
  Samples carving_samples;
  CarvingOptions carving;
  // The grid's own truncation, which its tricubic interpolant must not read across
  // (ContourOptions::zero_set).
  double zero_set_truncation = std::numeric_limits<double>::infinity();
};

// The fallback's reason where no contact point was kept at all (both reconstructions).
inline constexpr const char* kNoContactPoint =
    "no contact point was kept, so there is nothing to reconstruct a surface from";

// The local reconstruction on a grid that keeps no or few contact points (`few` says why): each
// cell without one takes its vertex from its edge crossings. Said through options.progress; an
// Error where options.fallback_to_mc is off. Nothing where `few` is empty.
void say_cells_from_crossings(const std::string& few, const ContourOptions& options);

// Why the contact points are too few for the values to be distances ("": they are not).
std::string contact_point_shortage(const GridSource& grid, const ContourOptions& options,
                                   const ContactPoints& cp);

// The Poisson reconstruction's inputs from the band (result.poisson_depth and
// result.sign_constraints set); `band_options` as the band was selected with. result.contact_points
// must still name their samples by index into `band.samples`.
ReconstructionInputs prepare_reconstruction(const BandSamples& band,
                                            const BandOptions& band_options, const GridSource& grid,
                                            const ContourOptions& options, ContourResult& result);

// GCP's or GTCP's mesh into result.mesh: screened Poisson reconstruction of
// result.contact_points, then (GCP) projection, carving and the undoing of moves that cross the
// mesh, clipped to the grid's box where the surface leaves it. Sets ContourResult::fallback
// where the mesh shows that the values were not distances.
// Projection onto the contact points and carving out of the samples' spheres, as `in` says, each
// move undone where it makes the mesh cross itself.
void refine_stage(const ReconstructionInputs& in, const ContourOptions& options,
                  ContourResult& result, Stages& stages);

void reconstruct_mesh(ReconstructionInputs inputs, const GridSource& grid,
                      const ContourOptions& options, ContourResult& result, Stages& stages);

/// True where GCP's local reconstruction runs brick by brick (reconstruct_in_bricks): a grid,
/// regular-triangulation gradients.
bool bricked_local(const GridView* grid, const ContourOptions& options);

/// GCP's local reconstruction from `grid` brick by brick (local_mesh_in_bricks), values scaled
/// by `band`'s value_scale: result.mesh, .local, .local_bricks. `grid_read` (optional): see
/// LocalBrickOptions::grid_read.
void reconstruct_in_bricks(const GridView& grid, const BandOptions& band,
                           const ContourOptions& options, ContourResult& result, Stages& stages,
                           const std::function<void()>& grid_read = {});
/// The same for a grid read a block at a time (its band's truncation given or none).
void reconstruct_in_bricks(const BlockedGrid& grid, const BandOptions& band,
                           const ContourOptions& options, ContourResult& result, Stages& stages);

/// The same from contact points made for the whole grid (GTCP's, the Delaunay or k-nearest
/// gradients', every sample's: result.contact_points, their samples named as in `points`).
void reconstruct_from_points(const GridView& grid, const BandOptions& band,
                             const GivenContactPoints& points, const ContourOptions& options,
                             ContourResult& result, Stages& stages);

/// contour() of a grid read a block at a time (a .vdb level set): marching cubes or GCP's local
/// reconstruction brick by brick, the values taken as distances (blocked_contour.cpp).
ContourResult contour_blocked_grid(const BlockedGridInput& input, const ContourOptions& given);

/// The outputs of a grid contoured in its own frame, placed in the world.
void place_in_world(const Eigen::Affine3d& world_from_grid, ContourResult& result);

}  // namespace sdfcontour::detail
