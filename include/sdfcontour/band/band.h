// The narrow band: which samples carry surface information for the triangulation methods.
// A sample far from the surface adds nothing to GCP but triangulation cost, and a sample at a
// truncation value (a TSDF or an OpenVDB level set clamps far values) carries no distance at
// all: both are left out before the triangulation.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "sdfcontour/input/samples.h"
#include "sdfcontour/input/sparse_grid.h"

namespace sdfcontour {

/// Values within this relative distance of a truncation value count as truncated: writers
/// store T in float32 and may round it.
inline constexpr double kTruncationTolerance = 1e-6;

/// Truncation distances found in (or given for) a field: values at or beyond them carry no
/// distance. Infinity where a sign is not truncated.
struct Truncation {
  double inside = std::numeric_limits<double>::infinity();   ///< of negative values
  double outside = std::numeric_limits<double>::infinity();  ///< of non-negative values
  bool detected() const {
    return inside < std::numeric_limits<double>::infinity() ||
           outside < std::numeric_limits<double>::infinity();
  }
  /// True if `value` is at a truncation distance of its sign (inline: whole-grid passes test
  /// millions of values).
  bool truncated(double value) const {
    const double t = value < 0 ? inside : outside;
    return std::abs(value) >= t * (1 - kTruncationTolerance);
  }
};

/// How values clamped at a truncation distance are recognised.
enum class TruncationMode {
  Auto,      ///< detect it (see detect_truncation)
  Given,     ///< BandOptions::truncation is the truncation distance
  None,      ///< every value is a distance
  Resolved,  ///< BandOptions::resolved (the whole grid's, for its blocks)
};

struct BandOptions {
  /// Keep samples with |value| <= band * spacing. Infinity keeps every sample (the paper's);
  /// 0 (the default) is auto_band() of the samples per axis.
  double band = 0;
  /// Samples up to `margin` spacings beyond the band (or inside a truncation distance) are
  /// triangulated too but give no contact point: they close the band's samples' stars, which
  /// would otherwise reach across the empty space beyond the band (and not be local).
  double margin = 1.0;
  TruncationMode truncation_mode = TruncationMode::Auto;
  /// With TruncationMode::Given: values with |value| >= truncation (to 1e-6 relative) are
  /// truncated and carry no distance.
  double truncation = 0;
  /// With TruncationMode::Resolved: the truncation found in the whole grid (a block's own values
  /// could show another).
  Truncation resolved;
  /// The factor that turns the values into distances (1 for a signed distance; 1/m for a field
  /// whose gradient norm is m). The band is measured, and the selected values returned, scaled.
  double value_scale = 1.0;
};

/// The rule for TruncationMode::Auto: per sign, let T be the largest |value| of that sign; the
/// sign is truncated at T if at least 64 samples, and at least `min_fraction` of that sign's
/// samples, have |value| >= T (1 - 1e-6). An exact SDF reaches its extreme at a few samples
/// (the grid's corners, a centre), a clamped one at a whole region. A half-space sampled on a
/// grid reaches it on a grid face, which is then dropped too: far from the surface, so the band
/// hides it anyway (TruncationMode::None keeps it).
Truncation detect_truncation(const Eigen::VectorXd& values, double min_fraction = 0.01);
Truncation detect_truncation(const GridView& grid, double min_fraction = 0.01);

/// detect_truncation's counts over one part of a grid (each sample in one part: Dask's bricks'
/// own samples): the part's extremes, its samples within the tolerance of them per sign, and its
/// negative and all samples.
struct TruncationCounts {
  double most_negative = 0, most_positive = 0;
  long at_inside = 0, at_outside = 0, negatives = 0, count = 0;
};
TruncationCounts truncation_counts(const GridView& part);

/// detect_truncation's rule on the parts' counts: a part's samples at its extreme count where
/// that extreme is the whole's (to the tolerance). One part gives detect_truncation's result.
Truncation truncation_of_parts(const std::vector<TruncationCounts>& parts,
                               double min_fraction = 0.01);

/// The truncation that `options` asks for on `values`.
Truncation resolve_truncation(const Eigen::VectorXd& values, const BandOptions& options);
Truncation resolve_truncation(const GridView& grid, const BandOptions& options);

/// The samples in the band, and where they came from.
struct BandSamples {
  Samples samples;           ///< the kept samples (positions and values)
  std::vector<long> source;  ///< for each kept sample, its index in the input (C order for grids)
  std::vector<char> core;    ///< for each kept sample, 1 if in the band proper (not the margin)
  double spacing = 0;        ///< the spacing h the band is measured in
  double band = 0;           ///< the band used, in spacings (auto resolved)
  /// Samples across the input's longest side (a grid's largest dimension): what the automatic
  /// choices (auto_band, auto_sign_constraints) go by.
  double samples_per_axis = 0;
  Truncation truncation;
  /// The largest |value| a core sample may have inside and outside, in distance units (the band,
  /// or a margin within the truncation distance; infinite for every sample).
  double core_inside = INFINITY, core_outside = INFINITY;
  /// Scattered samples dropped as isolated (fewer than 3 others within kIsolationReach spacings).
  long isolated = 0;
};

/// Scattered samples with fewer than 3 others this many spacings around are dropped as strays.
constexpr double kIsolationReach = 4;

/// The automatic band, in spacings, for samples `samples_per_axis` across: 8 below 128, 4 from
/// 128, 3 from 256. Measured against every sample (`bench/band.py`, docs/band.md, 6 shared meshes,
/// geometric mean of L1 / L1 with all samples): band 4 gives 1.068 at 32^3, 1.084 at 64^3, 1.120 at
/// 96^3 and 0.875 at 128^3; band 8 gives 1.017, 1.045 and 1.021 at 32^3, 64^3 and 96^3 for 31-60%
/// more time there. From 128 on, band 4 is as accurate as all samples and twice as fast as 8.
/// From 256, with the projection (on by default), band 3 against 4 took 0.74x (bunny 256^3) and
/// 0.79x (bunny 512^3) the time for 1.02x the L1 (docs/scale.md).
double auto_band(double samples_per_axis);

/// The automatic band of GCP's local reconstruction (LocalBrickOptions::band with band 0), in
/// spacings: 8 below 384 samples per axis, then auto_band's; with `lattice_points` (the lattice's
/// contact points, whose exact sphere search reads (band + 1)^2 columns per point) 6 from 128 to
/// 383. There band 6 against 8 gave 1.04x the L1 in 0.64x the time (five shared meshes at 128^3),
/// 1.05x in 0.77x (bunny, spot, armadillo at 256^3); at 64^3, 1.06x in 0.61x, but the torus lost
/// 1.40x and blub, the sphere 1.11x over the triangulation's band of 8, so below 128 it stays 8
/// (docs/lattice_contact_points.md). Its vertices fit the contact points
/// of the samples around their cells, and farther samples' points are still exact there: bunny
/// 128^3 L1 7.38e-5 (band 4) -> 6.54e-5 (6) -> 5.78e-5 (8), boot 4.08e-4 -> 3.84e-4 (8); bunny
/// 256^3 2.18e-5 (band 3) -> 2.03e-5 (4) -> 1.77e-5 (6) -> 1.61e-5 (8), boot 1.19e-4 -> 1.01e-4
/// (8), for 1.5-1.9x the time and up to 1.6x the memory (`bench/local.py --res 128,256 --methods mc
/// --variant b4:"--band 4" --variant b8:"--band 8"`). From 384 the
/// narrower band keeps large grids' time and memory (1024^3 within 4 GB).
double auto_local_band(double samples_per_axis, bool lattice_points);

/// The grid's samples with |value| <= (band + margin) * h (h the largest grid spacing) that are
/// not truncated, in C order; core flags those with |value| <= band * h and a margin inside the
/// truncation distance. Never builds the full grid's positions.
BandSamples select_band(const GridView& grid, const BandOptions& options);
BandSamples select_band(const Grid& grid, const BandOptions& options);
/// The same for a sparse grid: the samples of its stored bricks, bit for bit the dense grid's
/// band wherever the bricks not stored lie outside it. Truncation is never detected.
BandSamples select_band(const SparseGrid& grid, const BandOptions& options);

/// The same for scattered samples; h is `spacing` if positive, else the side of a cube holding
/// one sample on average (measured in the box of the central 98% of the samples on each axis).
/// Isolated samples (a clump of fewer than 4 with no other within kIsolationReach * h) are
/// dropped and counted in BandSamples::isolated; throws Error if every sample is.
BandSamples select_band(const Samples& samples, const BandOptions& options, double spacing = 0);

/// Throws Error unless `band` is positive (infinity allowed), `margin` non-negative and finite,
/// and a given truncation positive and finite.
void validate_band_options(const BandOptions& options);

/// The number of grid edges whose ends differ in sign: about the surface's area over h^2.
long sign_change_edges(const GridView& grid);

/// The norm of the field's gradient at the grid points next to a sign change: 1 for a signed
/// distance, m for a distance scaled by m, and spread out for a field that is no distance (a
/// smooth implicit: |grad| varies along the surface). Central differences with steps h and 2h,
/// Richardson-extrapolated so that curvature does not bias them; stencils touching a truncated
/// value (see `truncation`) are left out.
struct GradientNormSummary {
  double low = NAN;     ///< 10th percentile
  double median = NAN;  ///< 50th percentile
  double high = NAN;    ///< 90th percentile
  long count = 0;       ///< points measured; the percentiles are NaN for fewer than 16
  /// The median of | norm * distance_value_scale(median) - 1 | over the points where the field
  /// is smooth (second differences over h and 2h under kSmoothCurvature): how far the slope of
  /// the (rescaled) values strays from 1 where a distance has no kink (edges, the medial axis).
  /// At most 0.01 for exact distances to the shared meshes where smooth_fraction >= 0.2; 0.03
  /// for a neural SDF. NaN for fewer than 16 such points.
  double smooth_spread = NAN;
  double smooth_fraction = 0;  ///< the share of the points measured that are smooth
  /// The slope that decides whether the values are rescaled into distances
  /// (distance_value_scale): the median, or 1 (the values as given) unless the points where the
  /// field has no kink within two samples (second differences under kSmoothCurvature times the
  /// norm, at any scale) are off 1 too. Central differences across a thin part or a medial axis
  /// read both sides and measure less than the slope (the hammer at 32^3: 0.90 over all points,
  /// and no point without a kink). With fewer than 16 such points, the median is taken only
  /// where it is off 1 by more than kScaledSlope (a field scaled outright).
  double slope = 1;
};

/// How far the median norm over every point must be from 1 to rescale a field with no kinkless
/// point: thin shapes measure 0.76-0.90 (the plane at 16^3, the sword at 64^3, the hammer at
/// 32^3), a field scaled by 2 or 0.5 measures 2 or 0.5.
constexpr double kScaledSlope = 0.4;

/// Second differences (over h, and over 2h halved) below this many spacings count as smooth
/// for GradientNormSummary::smooth_spread: kinks measure ~0.3 or more (a turn of 20 degrees),
/// a curvature radius of 7 spacings 0.15.
constexpr double kSmoothCurvature = 0.15;
GradientNormSummary gradient_norm_summary(const GridView& grid, const Truncation& truncation = {});

/// The norms behind gradient_norm_summary, at the samples of `grid` (a block of its whole grid,
/// GridGeometry::first and whole) whose whole-grid indices lie in [own_first, own_end): blocks
/// that own disjoint parts give together the whole grid's norms. The block must hold 2 samples
/// beyond the owned ones, where the whole grid has them (throws Error otherwise).
struct CrossingNorms {
  std::vector<double> all;       ///< every point's norm
  std::vector<double> kinkless;  ///< those without a kink (GradientNormSummary::slope)
};
CrossingNorms crossing_gradient_norms(const GridView& grid, const Truncation& truncation,
                                      std::array<int, 3> own_first, std::array<int, 3> own_end);
/// The percentiles of `norms.all` (any order) and the slope (GradientNormSummary::slope).
GradientNormSummary summarize_gradient_norms(CrossingNorms norms);

/// The factor that turns values changing by `slope` per unit length near the surface into
/// distances (GradientNormSummary::slope): 1 / slope where that is more than 10% from 1, else 1.
/// Throws Error where 1 / slope overflows (subnormal values).
double distance_value_scale(double slope);

/// The band's samples proper, without the margin that only closes their stars.
Samples core_samples(const BandSamples& band);

}  // namespace sdfcontour
