// GCP contact points of a grid's band from the lattice alone, without a triangulation.
//
// On a grid a sample's neighbours are known in advance: its gradient comes from finite
// differences along the grid's axes (central, of fourth order where five samples are smooth,
// one-sided on the smoother side where a second difference says a crease or a medial axis lies
// between the samples: ENO), and the filter tests the candidate c = p - value * n against every
// band sample whose sphere can hold it, found through the grid's columns. That test is the
// power-cell test of the regular triangulation's neighbours, over a superset of them: it keeps
// exactly the points that lie in no band sample's sphere (to the tie tolerance).
#pragma once

#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour {

/// The lattice's contact points' tie tolerance (ContactPointOptions::tie_tolerance for them)
/// unless one is given: a candidate that another sample's sphere holds by less than a
/// thousandth of the two samples' distance is kept. At 1e-6, as the triangulation's, about a
/// third of a band of 8's candidates are held, mostly by 1e-3-1e-1 spacings near medial axes, and
/// their rescues take 40-46% of the run; 1e-3 lowers the L1 above by 4-11% for 0.67-0.99x the time
/// (docs/results/lattice_rescue_s36.md; pipeline.h's auto_lattice_points).
constexpr double kLatticeTieTolerance = 1e-3;

/// The contact points of `band`'s core samples (select_band of the grid `grid` describes: its
/// dims and spacing; `band.source` indexes it in C order). `options`:
///   tie_tolerance: as ContactPointOptions says, against every band sample's sphere;
///   max_slope_miss: the 26 lattice neighbours in the band stand for the triangulation's;
///   sphere_slide_rounds: as for the triangulation, out of every sphere that holds the point;
///   power_vertex_tolerance: a slid point is kept where its power to every sphere that holds it
///   is within this fraction of value^2 (where spheres nearly meet), and a sample without a point
///   then takes a vertex of its power cell among the spheres near where its gradient points
///   whose power to its own sphere is within it (where it meets three others, as the
///   triangulation's power vertices); 0: only a point that no sphere holds;
///   near_miss_tolerance, try_tet_gradients: not used.
/// With `only` (one flag per band sample), just the flagged samples give points.
/// A flagged sample reads the band samples within lattice_contact_reach samples of it; a
/// block's result equals the whole grid's for samples that far from the block's inner sides.
ContactPoints lattice_contact_points(const GridGeometry& grid, const BandSamples& band,
                                     const ContactPointOptions& options = {},
                                     const std::vector<char>* only = nullptr);

/// How far (in samples, along each axis) a sample's contact point reads the band when no band
/// sample's |value| exceeds `largest` (distance units; the whole grid's bound, not a block's): the
/// sphere filter's reach (three times `largest` with a slide, twice without) and the stencils' 3.
int lattice_contact_reach(const GridGeometry& grid, double largest,
                          const ContactPointOptions& options);
/// The same with `largest` in (the smallest) spacings.
int lattice_contact_reach(double largest_in_spacings, const ContactPointOptions& options);

}  // namespace sdfcontour
