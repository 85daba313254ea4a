// contour()'s contact points: GCP's (in bricks, or from one triangulation of the band) or GTCP's.
#include <algorithm>
#include <cmath>
#include <functional>

#include "pipeline/pipeline_stages.h"

namespace sdfcontour::detail {

namespace {

// GCP's gradients at the band's samples, from a whole triangulation or from neighbours.
PointMatrix sample_gradients(const Samples& s, const SampleTriangulations& t,
                             const ContourOptions& options) {
  switch (options.gradient_source) {
    case GradientSource::Knn:
      return knn_gradients(s.points, s.values, options.knn);
    case GradientSource::Delaunay:
      return vertex_gradients(s.points, s.values, *t.delaunay, options.gradient);
    case GradientSource::Auto:  // the triangulation's, off the local reconstruction's bricks
    case GradientSource::Regular:
    case GradientSource::Lattice:  // refused before (contact_point_stage)
      break;
  }
  return vertex_gradients(s.points, s.values, *t.regular, options.gradient);
}

}  // namespace

SampleTriangulations contact_point_stage(const BandSamples& band, const AnalyticShape* shape,
                                         const ContourOptions& options, ContourResult& result,
                                         Stages& stages) {
  const Method method = options.method;
  const Samples& s = band.samples;
  if (options.gradient_source == GradientSource::Lattice)
    throw Error(
        "lattice gradients run with GCP's local reconstruction of a grid: use --gradient regular "
        "here");
  const std::string n = std::to_string(s.values.size());
  // Only the band proper gives contact points; its margin closes their stars. (The local
  // reconstruction took the margin's too for a while: cube 128^3 L1 8.6e-5 -> 2.5e-6, bunny
  // 1.34e-4 -> 1.27e-4. But a margin sample's star reaches across the empty space beyond the
  // band, so bricks cannot certify it without triangulating most of the band again: contact
  // points took 621 s instead of ~10 s on cube 128^3, 212 s on bunny. Reverted until margin
  // stars can be bounded locally.)
  const std::vector<char>* core = &band.core;
  const std::string n_core = std::to_string(std::count(band.core.begin(), band.core.end(), 1));
  if (method == Method::Gtcp && (options.want_points || options.want_mesh))
    result.contact_points =
        stages.run("contact_points", "exact contact points of " + n_core + " samples",
                   [&] { return exact_contact_points(s.points, *shape, core); });

  // --points with any method but gtcp gives GCP contact points.
  const bool need_gcp = (options.want_points && method != Method::Gtcp) ||
                        (method == Method::Gcp && options.want_mesh);
  // GCP from the regular triangulation runs brick by brick (the same points, less memory).
  // Bricks need a band (or a truncation): without one, the weights are unbounded and no halo
  // is local.
  const double largest = s.values.size() ? s.values.cwiseAbs().maxCoeff() : 0.0;
  const bool bounded = std::isfinite(options.band.band) || (std::isfinite(band.truncation.inside) &&
                                                            std::isfinite(band.truncation.outside));
  const bool regular = options.gradient_source == GradientSource::Regular ||
                       options.gradient_source == GradientSource::Auto;
  const bool gcp_in_bricks = need_gcp && regular && options.bricks.size != 0 && bounded;
  const bool need_regular =
      (need_gcp && !gcp_in_bricks) || (method == Method::MtRt && options.want_mesh);
  const bool need_delaunay = (method == Method::MtDt && options.want_mesh) ||
                             (need_gcp && options.gradient_source == GradientSource::Delaunay);
  // GCP's triangulation: the margin closes the band's stars without hiding its samples
  // (capped_weight_values); MT-RT's is the paper's.
  const bool capped = method != Method::MtRt &&
                      (std::isfinite(band.core_inside) || std::isfinite(band.core_outside));
  TriangulationOptions topt;
  topt.parallel = options.parallel;
  SampleTriangulations t;
  if (need_regular) {
    topt.kind = TriangulationKind::Regular;
    t.regular = stages.run("triangulation", "regular triangulation of " + n + " samples", [&] {
      return triangulate(
          s.points,
          capped ? capped_weight_values(s.values, band.core_inside, band.core_outside) : s.values,
          topt);
    });
    result.hidden = t.regular->hidden_count;
  }
  if (need_delaunay) {
    topt.kind = TriangulationKind::Delaunay;
    t.delaunay = stages.run("delaunay_triangulation", "Delaunay triangulation of " + n + " samples",
                            [&] { return triangulate(s.points, s.values, topt); });
  }
  if (gcp_in_bricks) {
    BrickOptions bricks = options.bricks;
    if (bricks.halo == 0) bricks.halo = auto_brick_halo(largest, band.spacing);
    if (capped) {
      bricks.weight_cap_inside = band.core_inside;
      bricks.weight_cap_outside = band.core_outside;
    }
    bricks.cancel = options.cancel;
    result.contact_points =
        stages.run("contact_points", "triangulation, gradients and contact points in bricks", [&] {
          std::function<void(int, int)> report = [&](int done, int total) {
            check_cancel(options.cancel);
            if (options.progress_fraction) options.progress_fraction("bricks", done, total);
          };
          BrickStats st;
          ContactPoints cp = brick_contact_points(s, band.spacing, options.gradient,
                                                  options.contact, bricks, &st, report, core);
          result.bricks = st;
          return cp;
        });
    result.hidden = result.contact_points->hidden;
  } else if (need_gcp) {
    const PointMatrix gradients = stages.run("gradients", "gradients at " + n + " samples",
                                             [&] { return sample_gradients(s, t, options); });
    result.contact_points = stages.run("contact_points", "contact points and filter", [&] {
      return gradient_contact_points(s.points, s.values, gradients, *t.regular, options.contact,
                                     core);
    });
  }
  return t;
}

}  // namespace sdfcontour::detail
