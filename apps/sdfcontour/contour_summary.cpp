// sdfcontour contour's summary: the --stats JSON and the lines on stdout.
#include "contour_summary.h"

#include <iomanip>
#include <iostream>
#include <limits>

#include "sdfcontour/contact_points/contact_point_errors.h"
#include "sdfcontour/pipeline/option_ranges.h"

namespace sdfcontour::cli {

namespace {

// |value| and normal alignment of contact points against an exact SDF.
nlohmann::json errors_json(const ContactPoints& cp, const AnalyticShape& shape, double spacing) {
  const ContactPointErrors e = contact_point_errors(cp.points, cp.normals, shape);
  const Summary value = summarize(e.abs_value), alignment = summarize(e.alignment);
  nlohmann::json j;
  j["abs_value_median"] = value.median;
  j["abs_value_p95"] = value.p95;
  j["abs_value_mean"] = value.mean;
  j["normal_alignment_median"] = alignment.median;
  j["normal_alignment_mean"] = alignment.mean;
  if (spacing > 0) {
    j["spacing"] = spacing;
    j["abs_value_median_in_spacing"] = value.median / spacing;
    j["abs_value_p95_in_spacing"] = value.p95 / spacing;
  }
  return j;
}

// The band, its bricks and what the checks before the reconstruction measured.
void add_input_checks(nlohmann::json& j, const ContourArgs& a, const ContourResult& r) {
  if (r.band_samples > 0) {
    nlohmann::json band = {{"band", a.band},
                           {"band_spacings", r.band_spacings},
                           {"spacing", r.band_spacing},
                           {"samples", r.band_samples},
                           {"isolated_samples_dropped", r.isolated_samples},
                           {"truncation_detected", r.truncation.detected()}};
    if (r.truncation.inside < std::numeric_limits<double>::infinity())
      band["truncation_inside"] = r.truncation.inside;
    if (r.truncation.outside < std::numeric_limits<double>::infinity())
      band["truncation_outside"] = r.truncation.outside;
    j["band"] = band;
  }
  if (r.bricks)
    j["bricks"] = {{"size", r.bricks->size},
                   {"count", r.bricks->bricks},
                   {"retries", r.bricks->retries},
                   {"samples_triangulated", r.bricks->triangulated},
                   {"largest_brick_samples", r.bricks->largest_brick}};
  if (r.hidden >= 0) j["hidden_samples"] = r.hidden;
  if (r.gradient_norm > 0) {
    j["gradient_norm"] = r.gradient_norm;
    j["gradient_norm_percentiles"] = {r.gradient_norms.low, r.gradient_norms.median,
                                      r.gradient_norms.high};
    if (std::isfinite(r.gradient_norms.smooth_spread)) {
      j["gradient_norm_smooth_spread"] = r.gradient_norms.smooth_spread;
      j["gradient_norm_smooth_fraction"] = r.gradient_norms.smooth_fraction;
    }
  }
  if (r.approximate_distances) j["approximate_distances"] = true;
  if (r.fallback.empty() && a.method == "gcp") {
    j["off_zero_set"] = r.off_zero_set;
    j["clipped_to_grid"] = r.clipped_to_grid;
  }
  if (r.noise_level > 0) j["noise_level"] = r.noise_level;
  if (r.fallback.empty() && (a.method == "gcp" || a.method == "gtcp"))
    j["pieces_removed"] = r.pieces_removed;
  if (r.fallback.empty() && a.method == "gcp") {
    j["sign_constraints"] = r.sign_constraints;
    j["sign_violations"] = r.sign_violations;
    j["sign_violations_left"] = r.sign_violations_left;
    j["sign_constraints_dropped"] = r.sign_constraints_dropped;
  }
}

// What each stage after the contact points did (local reconstruction, projection, carving,
// adaptivity, untangling, side repair).
void add_stage_counts(nlohmann::json& j, const ContourOptions& opt, const ContourResult& r) {
  if (r.local_bricks)
    j["local_bricks"] = {{"bricks", r.local_bricks->bricks},
                         {"wider_halos", r.local_bricks->wider_halos},
                         {"contact_points", r.local_bricks->contact_points},
                         {"thin_parts", r.local_bricks->thin_parts},
                         {"edge_fans", r.edge_fans},
                         {"gradient", r.local_bricks->lattice_points ? "lattice" : "regular"}};
  if (r.subspacing_gaps)
    j["subspacing_gaps"] = {{"gaps", r.subspacing_gaps->gaps},
                            {"crossings", r.subspacing_gaps->crossings}};
  if (r.local)
    j["local"] = {{"cells", r.local->cells},
                  {"vertices", r.local->vertices},
                  {"split_cells", r.local->split_cells},
                  {"crossing_cells", r.local->crossing_cells},
                  {"feature_vertices", r.local->feature_vertices},
                  {"field_misses", r.local->field_misses},
                  {"thin_points", r.local->thin_points},
                  {"clamped", r.local->clamped}};
  if (r.mesh && (opt.method == Method::Gcp || opt.method == Method::Gtcp))
    j["reconstruction"] = reconstruction_name(r.reconstruction);
  if (r.projection)
    j["projection"] = {{"vertices_moved", r.projection->vertices_moved},
                       {"largest_move", r.projection->largest_move}};
  if (r.carving)
    j["carving"] = {{"vertices_moved", r.carving->vertices_moved},
                    {"largest_move", r.carving->largest_move},
                    {"held_back", r.carving->held_back},
                    {"passes", r.carving->passes},
                    {"side_violations", r.carving->side_violations},
                    {"side_violations_left", r.carving->side_violations_left},
                    {"wrong_side_left", r.carving->wrong_side_left},
                    {"side_passes", r.carving->side_passes}};
  if (r.adaptivity)
    j["adaptivity"] = {{"triangles_before", r.adaptivity->triangles_before},
                       {"triangles_after", r.adaptivity->triangles_after},
                       {"merges", r.adaptivity->merges},
                       {"freeze_rounds", r.adaptivity->freeze_rounds},
                       {"fitted_vertices", r.adaptivity->fitted_vertices}};
  if (r.untangling)
    j["untangling"] = {{"rounds", r.untangling->rounds},
                       {"vertices_reverted", r.untangling->vertices_reverted},
                       {"intersections_found", r.untangling->intersections_found},
                       {"intersections_left", r.untangling->intersections_left}};
  if (r.side_repair)
    j["side_repair"] = {{"wrong_side", r.side_repair->wrong_side},
                        {"repaired", r.side_repair->repaired},
                        {"left", r.side_repair->left},
                        {"vertices_moved", r.side_repair->vertices_moved}};
}

// The contact points kept (the bricks' are in "local_bricks"), with their errors against a
// built-in shape.
void add_contact_points(nlohmann::json& j, const ContourArgs& a, const ContourOptions& opt,
                        const LoadedInput& in, const ContourResult& r, const GridView* grid) {
  if (!r.contact_points || r.local_bricks) return;
  const ContactPoints& cp = *r.contact_points;
  nlohmann::json c = {
      {"kept", cp.size()},         {"hidden", cp.hidden},      {"zero_gradient", cp.zero_gradient},
      {"discarded", cp.discarded}, {"rescued_fn", cp.rescued}, {"file", a.points}};
  if (opt.method != Method::Gtcp) {
    // (Off the local reconstruction's bricks, 'auto' is the regular triangulation.)
    const std::string gradient = a.gradient == "auto" ? "regular" : a.gradient;
    c["gradient"] = gradient == "knn" ? "knn" + std::to_string(a.knn) : gradient + "/" + a.weights;
    c["tie_tolerance"] = opt.contact.tie_tolerance;
    c["fn"] = a.fn;
  }
  if (in.shape) c["error"] = errors_json(cp, *in.shape, grid ? grid->spacing().maxCoeff() : 0.0);
  j["contact_points"] = c;
}

// Seconds per stage (a stage that runs twice sums its runs), per Poisson and local step.
void add_seconds(nlohmann::json& j, const ContourResult& r) {
  double total = 0;
  nlohmann::json stage_json = nlohmann::json::object();
  for (const auto& s : r.stages) {  // a stage that runs twice (untangling) sums its runs
    stage_json[s.name] = stage_json.value(s.name, 0.0) + s.seconds;
    total += s.seconds;
  }
  j["seconds"] = stage_json;
  if (!r.poisson_stages.empty()) {
    nlohmann::json poisson_json = nlohmann::json::object();
    for (const auto& s : r.poisson_stages) poisson_json[s.name] = s.seconds;
    j["poisson_seconds"] = poisson_json;
  }
  if (!r.local_stages.empty()) {
    nlohmann::json local_json = nlohmann::json::object();
    for (const auto& s : r.local_stages) local_json[s.name] = s.seconds;
    j["local_seconds"] = local_json;  // summed over the bricks: CPU seconds
  }
  j["seconds_total"] = total;
}

}  // namespace

nlohmann::json contour_summary_json(const ContourArgs& a, const ContourOptions& opt,
                                    const LoadedInput& in, const ContourResult& r) {
  nlohmann::json j;
  j["input"] = a.input;
  j["method"] = a.method;
  j["samples"] = r.samples;
  const GridView* grid = grid_view_of(in.input);
  if (grid) j["grid"] = grid->dims;
  if (const auto* blocked = std::get_if<BlockedGridInput>(&in.input))
    j["grid"] = blocked->grid.dims;
  add_input_checks(j, a, r);
  add_stage_counts(j, opt, r);
  if (r.smoothed) j["smoothed"] = {{"sigma_samples", 1.0}};
  if (r.value_scale != 1) j["value_scale"] = r.value_scale;
  if (!r.fallback.empty()) j["fallback"] = {{"method", "mc"}, {"reason", r.fallback}};
  if (r.poisson_depth > 0) j["poisson_depth"] = r.poisson_depth;
  if (r.mesh)
    j["mesh"] = {{"vertices", r.mesh->vertices.rows()},
                 {"triangles", r.mesh->triangles.rows()},
                 {"file", a.output}};
  add_contact_points(j, a, opt, in, r, grid);
  add_seconds(j, r);
  return j;
}

void print_contour_summary(const ContourResult& r, double total) {
  std::cout << "samples " << r.samples;
  if (r.band_samples > 0) std::cout << ", in band " << r.band_samples;
  if (r.hidden >= 0) std::cout << ", hidden " << r.hidden;
  // (The bricks' contact points, kept for adaptivity or --points, name no samples: the bricks'
  // line counts.)
  if (r.contact_points && !r.local_bricks)
    std::cout << ", contact points kept " << r.contact_points->size();
  if (r.local_bricks)
    std::cout << ", contact points " << r.local_bricks->contact_points << " (over "
              << r.local_bricks->bricks << " bricks)";
  if (r.mesh)
    std::cout << ", mesh " << r.mesh->vertices.rows() << " vertices / " << r.mesh->triangles.rows()
              << " triangles";
  std::cout << "\nseconds:" << std::fixed << std::setprecision(3);
  for (const auto& s : r.stages) std::cout << " " << s.name << " " << s.seconds;
  std::cout << " (total " << total << ")" << std::endl;
}

}  // namespace sdfcontour::cli
