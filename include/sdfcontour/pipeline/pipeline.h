// The whole contouring pipeline, stage by stage, for the command line and the tests.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/band/subspacing_gaps.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/input/builtin_shapes.h"
#include "sdfcontour/input/noise.h"
#include "sdfcontour/input/sdf_input.h"
#include "sdfcontour/io/npy.h"
#include "sdfcontour/metrics/self_intersections.h"
#include "sdfcontour/reconstruction/adaptivity.h"
#include "sdfcontour/reconstruction/contact_projection.h"
#include "sdfcontour/reconstruction/local_brick.h"
#include "sdfcontour/reconstruction/local_reconstruction.h"
#include "sdfcontour/reconstruction/poisson.h"
#include "sdfcontour/reconstruction/side_repair.h"
#include "sdfcontour/reconstruction/sphere_carving.h"

namespace sdfcontour {

enum class Method { Gcp, Gtcp, Mc, MtRt, MtDt };

/// "gcp", "gtcp", "mc", "mt-rt", "mt-dt" <-> Method; parse_method throws Error for other names.
Method parse_method(const std::string& name);
std::string method_name(Method method);

/// Where GCP's per-sample gradients (and the sphere filter's neighbours) come from.
enum class GradientSource {
  Auto,      ///< Lattice for GCP's local reconstruction of a grid auto_lattice_points takes (of
             ///< exact distances: not with zero_set), else Regular
  Regular,   ///< the regular triangulation's tetrahedra (the paper)
  Delaunay,  ///< the Delaunay triangulation's tetrahedra
  Knn,       ///< least squares over the k nearest samples
  Lattice,   ///< a grid's own lattice: finite differences, every sphere in reach tested
             ///< (lattice_contact_points.h); grids on the local reconstruction only
};

/// "auto", "regular", "delaunay", "knn", "lattice" <-> GradientSource; parse throws Error for
/// other names.
GradientSource parse_gradient_source(const std::string& name);
std::string gradient_source_name(GradientSource source);

/// Whether GCP's local reconstruction can run brick by brick with these gradients: the regular
/// triangulation's (certified stars) or the lattice's (or the choice between them).
inline bool local_gradients(GradientSource source) {
  return source == GradientSource::Auto || source == GradientSource::Regular ||
         source == GradientSource::Lattice;
}

/// Whether GradientSource::Auto takes the lattice's contact points for GCP's local
/// reconstruction of a grid `samples_per_axis` across (its largest dimension): from 64. Measured
/// against the regular triangulation's (the local reconstruction's L1 and time, geometric means
/// over the shared meshes, 2 cores; docs/lattice_contact_points.md): 64^3 0.849x the L1 in 1.11x
/// the time, 128^3 0.938x in 0.99x, 256^3 0.874x in 0.74x, 512^3 0.909x in 0.67x; at 32^3
/// 1.062x (the cube 1.91x, the plane 1.45x), so coarser grids keep the triangulation. (All on a
/// band of 8; from 128 the lattice's auto band is now 6: band.h's auto_local_band.)
bool auto_lattice_points(double samples_per_axis);

/// How GCP's mesh is made from its contact points: the paper's global screened Poisson solve
/// (with projection, carving and their repairs), or the local reconstruction
/// (local_reconstruction.h: a vertex per surface cell from the contact points near it).
enum class Reconstruction { Auto, Poisson, Local };

/// "auto", "poisson", "local" <-> Reconstruction; parse throws Error for other names.
Reconstruction parse_reconstruction(const std::string& name);
std::string reconstruction_name(Reconstruction reconstruction);

/// Whether Reconstruction::Auto takes the local reconstruction for a grid `samples_per_axis`
/// across (its largest dimension): at every size. The 17 shared meshes' L1 over MC's (geometric
/// means): 16^3 local 0.264x against Poisson's 0.275x, 32^3 0.217x against 0.311x, 64^3 0.200x
/// against 0.337x; 256^3 0.505x against 0.590x (bunny and spot) in about the time
/// (`bench/local.py --res 16,32,64 --methods mc,gcp-local,gcp-poisson`).
bool auto_local_reconstruction(double samples_per_axis);

/// The local reconstruction's subdivisions for a grid `samples_per_axis` across (its largest
/// dimension): 2 below 64, else 1, and then auto_split_sag's edges once more. At 64^3 one level
/// and a split at 0.002 h against two levels and a split at 0.004 h, over the 17 shared meshes:
/// 0.72x the time and 0.49x the triangles for 1.03x the L1 (hammer 1.15x, blub 1.10x; every mesh
/// within 1.08x of the L1 issue 64 was filed against); at 32^3 the hammer's went to 1.14x that,
/// so two levels stay below 64 (`bench/local.py --res 32,64 --methods mc --variant def:""
/// --variant s1a:"--subdivisions 1 --split-sag 0.002"`, docs/results/one_level_64_s57.md). On a
/// smooth surface the sag is all of the error: the analytic torus at 64^3 is 4.4e-4 h from its
/// triangles' centroids on average against two levels' 2.4e-4 h (marching cubes' 1.3e-2 h), for
/// 0.65x their triangles. At 128^3 a second uniform level is 2% closer than one level and the
/// split, for 2.5x the triangles and 1.7x the time; at 256^3 no uniform level is 1.29x-1.42x the
/// L1.
int auto_subdivisions(double samples_per_axis);

/// The local reconstruction's split_sag (LocalBrickOptions) for a grid `samples_per_axis` across:
/// 0.002 spacings from 64 to 95 (one uniform level where 32^3 keeps two: 0.004 there left blub's
/// L1 1.15x, spot's 1.08x the two levels'), else 0.004. The 17 shared meshes' L1 over MC's
/// (geometric means, `bench/local.py --res 32,64,128 --methods mc,gcp-local --variant
/// nosplit:"--split-sag 0"`): 128^3 0.390x -> 0.356x for 1.6x the triangles, 32^3 0.295x ->
/// 0.292x; the analytic torus at 256^3 splits no edge (its chords sag less).
double auto_split_sag(double samples_per_axis);
/// Whether the local reconstruction looks for parts thinner than a spacing
/// (LocalBrickOptions::thin_parts) on a grid `samples_per_axis` across: below 192, where the grid
/// at twice the resolution with one subdivision fewer replaces the grid's own cells (the 17 shared
/// meshes' L1 over MC's, `bench/local.py --methods mc,gcp-local-thin --variant
/// thick:"--thin-parts off"`: 32^3 0.292x -> 0.216x, 64^3
/// 0.253x -> 0.199x, 128^3 0.356x -> 0.267x without the exact cube, 0.193x -> 0.272x with it; the
/// sword's blade and the plane's wings appear). An exact axis-aligned box loses its exactness on
/// that grid (at 128^3 from 1e-5 to 0.36x MC's: its narrow cells next to the edges hold one or two
/// contact points, one of them often with a bent normal). Not from 192: at 256^3 the exact cube
/// is 1.02x MC's with it, and it costs twice the time and 2-3x the memory (docs/notes/local.md).
bool auto_thin_parts(double samples_per_axis);
/// The same, knowing the grid's `gaps` (count_subspacing_gaps): on below 192 samples per axis,
/// and from 192 up to kThinPartGridLimit where at least kThinPartGapShare of the edges that the
/// surface crosses are subspacing gaps. At 256^3 the sword has 23% (its blade appears, 0.81x ->
/// 0.08x MC's L1, for 5x the time and 12x the memory) and the boot 0.38% (its tread's slots: L1
/// 0.72x, L-infinity 0.58x, for 1.6x the time and 2.4x the memory; on the lattice's contact points
/// it was otherwise 1.12x the L1 of the default that issue 64 was filed against). The plane has
/// 0.13% and stays off (0.78x the L1 for 2x the time and 4.4x the memory); every other shared mesh
/// is under 0.1% (docs/results/issue64_accuracy.md).
bool auto_thin_parts(double samples_per_axis, const SubspacingGaps& gaps);
/// auto_thin_parts's share of subspacing gaps among the edges that the surface crosses.
constexpr double kThinPartGapShare = 0.0025;
/// The largest grid (samples per axis) on which auto_thin_parts may turn thin parts on: the finer
/// grid's values are dense doubles, (2n - 1)^3 of them in a brick whose halo spans ~70 samples
/// (1.2 GB peak for the sword at 256^3; 9 GB and 57 s at 512^3, against 0.6 GB and 6.6 s without).
constexpr int kThinPartGridLimit = 256;
/// Whether auto_thin_parts's choice needs the grid's gaps on a grid `samples_per_axis` across:
/// from 192 up to kThinPartGridLimit; elsewhere the size alone decides (no pass is made).
bool thin_parts_need_gaps(double samples_per_axis);

/// Whether the local reconstruction fans each grid edge's polygon (LocalReconstructionOptions::
/// edge_fans: a mesh right by construction, with no subdivision and no repair stage) on a grid
/// `samples_per_axis` across: from kEdgeFansFrom, where speed matters more than the last quarter
/// of the accuracy (bunny, spot and armadillo at 512^3: 0.37-0.44x the repaired mesh's time and
/// 0.43x its memory, at 0.41x marching cubes' L1 against 0.30x; bunny 384^3: 8.9 s against 21.7 s
/// at 1.36x the L1; 2.3-2.9x marching cubes' triangles against 5-6x; docs/edge_fans.md). Below it
/// the accuracy targets of issue 64 hold the repaired mesh's L1.
bool auto_edge_fans(double samples_per_axis);
/// auto_edge_fans's threshold (samples per axis); the automatic band is 3 spacings there too.
constexpr int kEdgeFansFrom = 384;

/// An option that is on, off, or chosen from the input.
enum class Switch { Auto, On, Off };
/// "auto", "on", "off" <-> Switch; throws Error "unknown WHAT 'NAME' (known: ...)" for others.
Switch parse_switch(const std::string& what, const std::string& name);

/// Whether GCP constrains the samples' sides by default, for samples `samples_per_axis` across:
/// below 128. Measured (docs/sides.md): on the shared meshes they lower GCP's L1 to 0.958x at
/// 32^3 and 0.974x at 64^3; on bunny, spot and armadillo they raise it by 1.5-9% at 128^3 and
/// 3.5-8% at 256^3 and 512^3, where the solved surface is already within the samples' noise.
bool auto_sign_constraints(double samples_per_axis);

/// The band, in spacings, of the samples whose balls carve GCP's mesh on a grid
/// `samples_per_axis` across with the band options `given`: 16 with the automatic band below 128
/// samples per axis (a user's band bounds every sample used); 0: the band's own samples.
double auto_carving_band(const BandOptions& given, double samples_per_axis);

/// Whether GCP carving's triangle rounds (CarvingOptions::side_passes) run by default, for samples
/// `samples_per_axis` across (a grid's largest dimension; for scattered samples and OpenVDB level
/// sets the band's extent in spacings): below 128. Above, they lower L1 by ~11% for 2.3-2.8x the
/// whole run's time (bunny 256^3: grid 3.98e-5 -> 3.55e-5 and 14 -> 40 s; .vdb of half width 3
/// 4.15e-5 -> 3.75e-5 and 14 -> 31 s).
bool auto_carve_sides(double samples_per_axis);

/// Whether a grid's values are no exact distances, by its gradient norms: the slope strays from
/// 1 by over 0.02 where the field is smooth (GradientNormSummary::smooth_spread), measured on at
/// least 20% of the crossings. Exact distances to the shared meshes at 16^3-128^3 read at most
/// 0.010 there (the torus at 64^3); the neural bunny's grid 0.032 (64^3), 0.037 (128^3).
/// Coarser grids, mostly kinks, are not judged (false).
bool auto_approximate_distances(const GradientNormSummary& norms);

/// ContourOptions::local_projection's and local's robust_rounds when the local reconstruction
/// chooses them.
constexpr int kAutoRobustRounds = -1;
/// local_projection_options() with its robust rounds left to the local reconstruction.
inline ContactProjectionOptions auto_local_projection() {
  ContactProjectionOptions p = local_projection_options();
  p.robust_rounds = kAutoRobustRounds;
  return p;
}

/// LocalReconstructionOptions with the cells' robust rounds left to the local reconstruction.
inline LocalReconstructionOptions auto_local_options() {
  LocalReconstructionOptions o;
  o.robust_rounds = kAutoRobustRounds;
  return o;
}

struct ContourOptions {
  Method method = Method::Gcp;
  bool want_mesh = true;     ///< produce the method's mesh
  bool want_points = false;  ///< produce contact points (GCP's, or GTCP's for method gtcp)
  GradientSource gradient_source = GradientSource::Auto;
  int knn = 18;  ///< k for GradientSource::Knn
  GradientOptions gradient;
  ContactPointOptions contact;
  /// contact.tie_tolerance for the lattice's contact points (the CLI's and Python's
  /// tie_tolerance set both when given).
  double lattice_tie_tolerance = kLatticeTieTolerance;
  /// The samples the triangulation methods use (every method but mc).
  BandOptions band;
  /// GCP with regular-triangulation gradients runs in bricks (size 0: one global triangulation).
  BrickOptions bricks;
  /// GCP's mesh. Auto: local for grids (auto_local_reconstruction), and for a grid read block by
  /// block (BlockedGridInput: a .vdb level set), which takes it or marching cubes. Local needs a
  /// grid's cells: scattered samples always take Poisson.
  Reconstruction reconstruction = Reconstruction::Auto;
  /// The local reconstruction's cells. Their robust_rounds is kAutoRobustRounds here: three, and
  /// none for edge fans on the grid itself (local_stage.cpp says why); any other value is taken
  /// as given.
  LocalReconstructionOptions local = auto_local_options();
  /// The local reconstruction's projection: a tighter neighbourhood than the Poisson path's and no
  /// residual limit (the subdivided mesh's new vertices are chords, not a smooth surface). Measured
  /// on bunny at 32^3 with 2 subdivisions: L1 2.14e-3 with the Poisson path's options, 1.37e-3.
  /// Two robust rounds at 0.03 spacings (bench/local.py --res 32,64 --methods gcp-local, every
  /// shared mesh): geometric mean L1 0.308x -> 0.305x MC's at 32^3, 0.287x -> 0.278x at 64^3
  /// (wingnut 64^3 0.271x -> 0.226x; 0.01 spacings: 0.310x / 0.280x). Chord offsets and a
  /// second fit within 2 spacings where the first has no height (with the local contact points'
  /// near misses): 0.305x -> 0.300x at 32^3, 0.278x -> 0.267x at 64^3; the analytic torus at
  /// 64^3 0.00086 h -> 0.00039 h, the sphere 0.00041 h -> 0.00016 h (bench/smooth_shapes.py).
  /// Crease planes (a vertex whose points lie on two facets goes onto their crease): bunny at
  /// 256^3 / 512^3 0.81x / 0.86x the L1, the shared meshes at 64^3 0.97x (docs/projection.md).
  /// Its robust_rounds is kAutoRobustRounds here: two, and none for edge fans on the grid itself
  /// (local_stage.cpp says why); any other value is taken as given.
  ContactProjectionOptions local_projection = auto_local_projection();
  /// The local reconstruction's lattice subdivisions (LocalBrickOptions::subdivisions) before its
  /// vertices are projected onto the contact points (`project`, `projection`); -1:
  /// auto_subdivisions.
  int subdivisions = -1;
  /// The local reconstruction's edges split once more where their chords sag by more than this
  /// many spacings (LocalBrickOptions::split_sag; grids, brick by brick); -1: auto_split_sag.
  double split_sag = -1;
  /// The local reconstruction's dual mesh on the grid at twice the resolution with the parts
  /// thinner than a spacing (LocalBrickOptions::thin_parts); Auto: auto_thin_parts.
  Switch thin_parts = Switch::Auto;
  /// The local reconstruction's edge fans on grids (LocalReconstructionOptions::edge_fans, which
  /// contour() sets from this): On, Off, or Auto: auto_edge_fans of the grid's size (or on where
  /// local.edge_fans is set already).
  Switch edge_fans = Switch::Auto;
  PoissonOptions poisson;  ///< reconstruction of gcp's and gtcp's meshes; depth 0: automatic
  /// GCP: the samples within sign_band spacings of the surface (in the band proper) constrain the
  /// indicator so that each ends on its own side of the mesh (poisson.h, SignedSamples). Auto:
  /// where auto_sign_constraints says so.
  Switch enforce_signs = Switch::Auto;
  double sign_band = 2.0;
  double sign_radius = 1.5;  ///< the correction's radius, in spacings (SignConstraintOptions)
  SignConstraintOptions sign_constraints;
  /// GCP: move the mesh out of the samples' spheres (sphere_carving.h): the band's samples, or
  /// on a grid below 128 samples per axis with the automatic band, every sample within 16
  /// spacings. Auto: on, except on values smoothed for noise (their spheres are not empty).
  Switch carve = Switch::Auto;
  CarvingOptions carving;
  /// GCP carving's triangle phase (CarvingOptions::side_passes). Auto: where auto_carve_sides
  /// says so, for every kind of input.
  Switch carve_sides = Switch::Auto;
  /// GCP: after carving and its untangling, dent the mesh off the samples still on the wrong side
  /// (side_repair.h). Auto: where carving's triangle phase ran.
  Switch side_repair = Switch::Auto;
  /// GCP: move the reconstructed mesh onto a local quadric fit of its contact points
  /// (contact_projection.h), before carving. Auto: on at every resolution (it was off from 128
  /// until measured: it gains more the finer the grid, L1 0.98x at 128^3 on bunny, spot and
  /// armadillo, 0.91x on bunny 256^3, 0.70x on bunny 512^3; docs/scale.md).
  Switch project = Switch::Auto;
  ContactProjectionOptions projection;
  /// GCP's local reconstruction: move the vertices (all, or those whose band samples mismatch
  /// distances to the mesh by more than zero_set_options.mismatch) onto the grid's tricubic
  /// zero set, uncarved (zero_set_refinement.h). Auto: on where the values are found no exact
  /// distances (detect_approximate), off elsewhere: on exact distances the contact points are
  /// the more accurate (every vertex refined where its samples mismatch by over 0.02: 0.300x ->
  /// 0.316x MC's L1 at 32^3, 0.267x -> 0.275x at 64^3, sharp edges farther).
  Switch zero_set = Switch::Auto;
  ZeroSetRefinementOptions zero_set_options;
  bool parallel = true;  ///< parallel triangulation (other stages follow TBB's thread limit)
  /// Called with a short message as each stage starts; empty for silence.
  std::function<void(const std::string&)> progress;
  /// Called as a long stage advances: (stage, done, total). Empty for silence.
  std::function<void(const std::string&, long, long)> progress_fraction;
  /// When set and it becomes true, contouring stops soon (at the next stage, brick or solver
  /// iteration) by throwing Cancelled.
  const std::atomic<bool>* cancel = nullptr;
  /// Fields that are not distances (a distance times m, a smooth implicit): on a grid, measure
  /// the slope next to the surface (GradientNormSummary::slope: where the field has no kink) and,
  /// if it is off 1 by more than 10%, rescale the values by its inverse before the band is chosen
  /// (all methods but mc and gtcp), once: nothing runs again on other values. Not less: an exact
  /// distance to a detailed mesh measures up to ~1% off at 64^3, and rescaling an exact distance
  /// by 1% hides most samples.
  bool normalize_values = true;
  /// Where GCP on a grid cannot trust the values as distances, it says so and goes on, decided
  /// once: values clamped within about a spacing of the surface (no sample can keep a contact
  /// point) take marching cubes' mesh from the start; on the local reconstruction, each cell
  /// without a contact point takes its vertex from its edge crossings (the run says when none or
  /// few have one); on the Poisson path, a mesh off the values' zero set, with more pieces than
  /// marching cubes', or from too few contact points is replaced by marching cubes' mesh.
  /// ContourResult::fallback says why marching cubes' mesh was returned. Without it, each of
  /// those cases throws Error instead.
  bool fallback_to_mc = true;
  /// GCP on a noisy grid (noise_level() above 5% of a spacing, times the gradient norm): the
  /// values are smoothed with a Gaussian of one sample first, and everything after runs on the
  /// smoothed grid (ContourResult::noise_level, smoothed). Noise of 0.1 h already leaves GCP
  /// almost no contact point, and 0.5 h gives marching cubes ~60 bubbles on a sphere.
  bool smooth_noise = true;
  /// GCP on a grid whose values are no exact distances where the field is smooth
  /// (GradientNormSummary::smooth_spread over kApproximateSpread: a neural SDF, a TSDF): the
  /// contact points miss by their samples' depth times the slope's error and the spheres are not
  /// empty, so the automatic choices become the local reconstruction with every vertex on the
  /// grid's tricubic zero set (zero_set), without carving (ContourResult::approximate_distances).
  bool detect_approximate = true;
  /// Merging the mesh where the surface is flat enough (reconstruction/adaptivity.h), after
  /// everything else: over the contact points for GCP and GTCP, the mesh's own planes otherwise.
  /// Tolerance 0 (the default): the mesh as it is.
  AdaptivityOptions adaptivity;
};

struct StageTime {
  std::string name;
  double seconds = 0;
};

/// `options` with LocalReconstructionOptions::edge_fans set from ContourOptions::edge_fans for a
/// grid `samples_per_axis` across (its largest dimension; auto_edge_fans): what contour() and
/// the brick functions of the Python module and Dask run with.
ContourOptions with_edge_fans(ContourOptions options, double samples_per_axis);

struct ContourResult {
  std::optional<Mesh> mesh;
  /// GCP's or GTCP's contact points. Without want_points, a GCP mesh's reconstruction takes
  /// their points and normals (freed there): only the counts and sample indices remain.
  std::optional<ContactPoints> contact_points;
  int samples = 0;                   ///< samples in the input
  int band_samples = 0;              ///< of those, in the band (triangulated); 0 for mc alone
  long isolated_samples = 0;         ///< scattered samples dropped as strays (BandSamples)
  double band_spacing = 0;           ///< the spacing h the band is measured in
  Truncation truncation;             ///< the truncation found or given
  std::optional<BrickStats> bricks;  ///< when GCP ran in bricks
  /// gcp, gtcp: the reconstruction that made the mesh (Poisson or Local, never Auto)
  Reconstruction reconstruction = Reconstruction::Poisson;
  std::optional<LocalReconstructionStats> local;  ///< when the local reconstruction ran
  std::optional<LocalBricksStats> local_bricks;   ///< when it ran brick by brick
  bool edge_fans = false;  ///< whether its mesh was edge-fanned (ContourOptions::edge_fans)
  /// The grid's subspacing gaps, when auto_thin_parts needed them.
  std::optional<SubspacingGaps> subspacing_gaps;
  int poisson_depth = 0;  ///< the depth the mesh was reconstructed at
  int hidden = -1;        ///< hidden samples of the regular triangulation, -1 if none was built
  std::vector<StageTime> stages;
  std::vector<StageTime> poisson_stages;  ///< inside the "poisson" stage, for gcp/gtcp meshes
  /// Inside the "local" stage run brick by brick: each step's seconds summed over the bricks.
  std::vector<StageTime> local_stages;
  double gradient_norm = 0;            ///< median |grad value| next to the surface, when measured
  GradientNormSummary gradient_norms;  ///< its 10th, 50th and 90th percentiles
  /// GCP on a grid: the fraction of the mesh's vertices more than a spacing off the field's zero
  /// set (trilinear; after rescaling). Over 1% means the values are no distances: see fallback.
  double off_zero_set = 0;
  double noise_level = 0;    ///< GCP on a grid: the values' noise_level(), in spacings
  double band_spacings = 0;  ///< the band used (auto resolved), in spacings
  int pieces_removed = 0;    ///< gcp, gtcp: pieces of the mesh smaller than a spacing, removed
  /// gcp on a grid whose surface runs out of it: the mesh was cut to the grid's box (the
  /// reconstruction closes it outside, where no sample says where it is)
  bool clipped_to_grid = false;
  /// gcp with enforce_signs: samples on the wrong side of the indicator before its correction,
  /// and after it (0 unless the sweeps ran out).
  long sign_violations = 0, sign_violations_left = 0;
  bool sign_constraints_dropped = false;  ///< they changed the topology: the solved surface kept
  bool sign_constraints = false;          ///< gcp: the samples' sides constrained the indicator
  std::optional<ContactProjectionStats> projection;  ///< gcp: when the mesh was projected
  std::optional<CarvingStats> carving;               ///< gcp: when the mesh was carved
  /// gcp: projection's and carving's moves undone where they made the mesh cross itself
  /// (self_intersections.h), summed over both stages
  std::optional<UntangleStats> untangling;
  std::optional<AdaptivityStats> adaptivity;  ///< with a positive adaptivity tolerance
  /// gcp, when carving's triangle phase ran: the samples still on the wrong side after the
  /// untangling, dented onto their sides (side_repair.h)
  std::optional<SideRepairStats> side_repair;
  bool smoothed = false;  ///< the values were smoothed (see ContourOptions::smooth_noise)
  /// The values were found no exact distances (ContourOptions::detect_approximate)
  bool approximate_distances = false;
  double value_scale = 1;  ///< the factor the values were rescaled by (1: none)
  std::string fallback;    ///< why marching cubes' mesh was returned instead of GCP's
};

/// The Poisson depth for samples `spacing` apart spanning `points`' extent: 7 up to 48 samples
/// per axis, 8 up to 129, 9 up to 257, 10 up to 513, 11 above, so that the mesh follows the
/// grid. Measured on the 17 shared meshes (bench/poisson_depth.py,
/// docs/results/poisson_depth.md): at 32^3 depth 7 gives GCP/MC L1 0.349 with 17x MC's
/// triangles, depth 8 0.376 with 61x; at 16^3 depth 7 0.306 with 78x, depth 8 0.317 with 100x;
/// at 64^3 depth 8 0.341, depth 7 0.390. Depth 6 (0.305 with 22x at 16^3 on grids) left a
/// spurious far sheet on 3000 random samples of a sphere: not used. Measured (bench/scale.py,
/// docs/scale.md): at
/// 256^3 depth 8 is coarser than the grid (GCP's L1 1.27x MC's) and depth 9 gives 0.59x; at 512^3
/// depth 9 gives 1.3-1.9x MC's L1 (bunny, spot, armadillo) and depth 10 0.57-0.95x; at 1024^3
/// depth 10 gives 1.43x MC's L1 (bunny, 6.9 GB) and depth 11 0.61-0.74x (bunny, spot, armadillo;
/// 6.1-8.4 GB). Deeper than 11 is left to the user (--depth): each depth needs ~4x the memory.
int auto_poisson_depth(const PointMatrix& points, double spacing);

/// The options of GCP's local reconstruction in bricks (local_brick.h) that `options` asks for:
/// its band (truncation as given), gradients, contact points, local options, subdivisions and
/// projection (ContourOptions::local_projection), and cancel flag.
LocalBrickOptions local_brick_options(const ContourOptions& options);

/// The largest |value|, in spacings of distance, that contour() reads from a grid of `dims` with
/// `options` (the local reconstruction aside: local_values_reach): the band with its margin, and
/// GCP's carving band. A sparse grid exact to here gives what the dense grid gives.
double contour_values_reach(const ContourOptions& options, const std::array<int, 3>& dims);

/// Runs `options.method` on `input`. Throws Error for an input the method cannot use (no sign
/// change, MC without a grid, GTCP, which needs contour_with_exact_sdf, no contact point kept).
ContourResult contour(const SdfInput& input, const ContourOptions& options);

/// The same for samples of a shape whose exact SDF is known (the built-in shapes): method GTCP
/// takes its contact points from `shape` (the paper's ground-truth contact points); the other
/// methods read the samples alone, as contour() does.
ContourResult contour_with_exact_sdf(const SdfInput& input, const AnalyticShape& shape,
                                     const ContourOptions& options);

}  // namespace sdfcontour
