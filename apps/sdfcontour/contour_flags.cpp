// sdfcontour contour's options: each flag, its help, and whether --help or --help-all lists it.
#include "contour_flags.h"

#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "cli_options.h"
#include "commands.h"
#include "sdfcontour/pipeline/option_ranges.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace sdfcontour::cli {

const std::array<ProjectionOption, 6> kProjectionOptions = {
    {{"--projection-radius", &ContactProjectionOptions::radius, 0.5, 8,
      "GCP Poisson path's projection: the fitted neighbourhood's radius, in spacings"},
     {"--projection-max-move", &ContactProjectionOptions::max_move, 0, 4,
      "GCP Poisson path's projection: a vertex whose fit is farther than this many spacings stays"},
     {"--projection-agreement", &ContactProjectionOptions::normal_agreement, -1, 1,
      "GCP Poisson path's projection: only contact points whose normal's cosine with the vertex's "
      "exceeds this are fitted"},
     {"--projection-depth-scale", &ContactProjectionOptions::depth_scale, 0, 1e6,
      "GCP Poisson path's projection: a point from a sample |value| away weighs 1 / (1 + (|value| "
      "/ "
      "(this many spacings))^2); 0: all the same"},
     {"--projection-variance", &ContactProjectionOptions::max_variance_factor, 1, 1e6,
      "GCP Poisson path's projection: the largest variance factor of a fitted height (1: a plain "
      "mean); a vertex whose fit is less certain stays"},
     {"--projection-residual", &ContactProjectionOptions::max_residual, 0, 1e6,
      "GCP Poisson path's projection: a vertex stays where the points' RMS distance from the "
      "fitted "
      "quadric exceeds this many spacings (0: no limit)"}}};

namespace {

// GCP's gradients, contact points and band.
void add_contact_point_options(CLI::App* c, ContourArgs& a) {
  c->add_option("--gradient", a.gradient,
                "GCP gradients from the regular or delaunay triangulation, knn least squares, or a "
                "grid's lattice (finite differences; the local reconstruction only); auto: the "
                "lattice for the local reconstruction of a grid with 64 or more samples along its "
                "longest axis, else regular")
      ->capture_default_str();
  c->add_option("--weights", a.weights, "Averaging of tet gradients: uniform, volume or james")
      ->capture_default_str();
  c->add_option("--knn", a.knn, "k for --gradient knn (the paper uses 6, 18, 26)")
      ->capture_default_str();
  c->add_option("--james-epsilon", a.james_epsilon,
                "Regularisation of the James weights' linear system")
      ->capture_default_str();
  c->add_option("--tie-tolerance", a.tie_tolerance,
                "Contact point c is discarded only if |c - p_n| < |value_n| - tol * |p_n - p|; "
                "0 is the strict test; auto: 1e-6 for the triangulation's points, 1e-3 for the "
                "lattice's")
      ->capture_default_str();
  c->add_option("--band", a.band,
                "Triangulation methods (all but mc) use only samples with |value| <= BAND "
                "grid spacings (scattered samples: the side of a cube holding one sample); "
                "'all' keeps every sample, as in the paper; 'auto': 8 below 128 samples per "
                "axis, 4 from 128, 3 from 256; GCP's local reconstruction (the default on grids) "
                "8 below 384 (with the lattice's contact points 6 from 128), 3 from 384")
      ->capture_default_str();
}

// The Poisson path's sign constraints, carving and side rounds.
void add_carving_options(CLI::App* c, ContourArgs& a) {
  a.poisson_path_options.push_back(
      c->add_flag("--sign-constraints", a.sign_constraints,
                  "GCP: correct the indicator where samples next to the surface would end on the "
                  "wrong side of the mesh (default: below 128 samples per axis, where it is more "
                  "accurate; finer grids are more accurate without)"));
  a.poisson_path_options.push_back(
      c->add_flag("--no-sign-constraints", a.no_sign_constraints,
                  "GCP: do not correct the indicator (the paper's reconstruction)"));
  c->add_flag("--no-carve", a.no_carve,
              "GCP: keep the reconstruction's vertices where they are; by default a vertex "
              "inside a sample's sphere (which holds no surface) moves onto it: the band's "
              "samples, or below 128 samples per axis with --band auto every sample within 16 "
              "spacings; not on values smoothed for noise");
  a.poisson_path_options.push_back(c->add_flag(
      "--no-side-repair", a.no_side_repair,
      "GCP carving: leave the samples that carving's untangling left on the wrong side of "
      "the mesh; by default (where --side-passes runs) each dents the nearest sheet onto "
      "its side where that crosses and folds nothing and moves no other sample's side"));
  c->add_option("--side-passes", a.side_passes,
                "GCP carving: rounds in which each sample within a spacing of the surface that a "
                "triangle cuts, or that lies on the wrong side of the mesh, moves the nearest "
                "triangle, edge or vertex behind its sphere; 0: vertices only; auto: 12 below 128 "
                "samples per axis (a .vdb's or scattered samples' band: its extent in spacings), "
                "0 above (bunny 256^3: 11% lower L1 for 2.3-2.8x the run's time)")
      ->capture_default_str();
}

// The reconstruction: local or Poisson, adaptivity, subdivisions, the local options.
void add_reconstruction_options(CLI::App* c, ContourArgs& a) {
  c->add_option(
       "--reconstruction", a.reconstruction,
       "GCP's mesh from its contact points: 'local' (a vertex per grid cell the surface "
       "crosses, from the contact points near it; topology from the samples' signs; "
       "brick by brick), 'poisson' (the paper's screened Poisson solve, then projection "
       "and carving), or 'auto' (local for grids, .vdb level sets and Python's callables: "
       "0.22x / 0.20x marching cubes' L1 on the shared meshes at 32^3 / 64^3, Poisson "
       "0.31x / 0.34x; docs/notes/local.md). A .vdb level set is then read box by box, never "
       "whole; scattered samples always take poisson")
      ->capture_default_str();
  c->add_option("--adaptivity", a.adaptivity,
                "Merge the mesh where the surface is flat enough: edges collapse while the merged "
                "vertex's squared distances to the tangent planes its region gathers (GCP's "
                "contact points, or the mesh's own planes for the other methods), summed, stay "
                "under this many spacings squared; creases and corners stay. 0 (default): the "
                "mesh as reconstructed")
      ->capture_default_str();
  c->add_option("--adaptivity-bricks", a.adaptivity_bricks,
                "Adaptivity merges brick by brick, in parallel: bricks of this many spacings, "
                "then again on bricks shifted by half a brick (across the first pass's seams). "
                "0: the whole mesh as one brick, sequential (the same mesh for any thread count "
                "either way); auto: 32 where the mesh spans at most 64 spacings (a 64^3 grid: "
                "half the time, 0.1-2.6% more triangles), else 64")
      ->capture_default_str();
  c->add_option("--adaptivity-fit", a.adaptivity_fit,
                "Adaptivity's last step: rounds of a least-squares fit that moves the merged "
                "vertices so that their triangles pass through the unmerged mesh's vertices, "
                "which lie on the surface, instead of cutting chords under it (bunny 256^3, "
                "--adaptivity 0.03: L1 2.41e-5 -> 2.06e-5, below the unmerged mesh's 2.44e-5). "
                "0: the merged vertices stay at their quadrics' minima")
      ->capture_default_str();
  a.local_options.push_back(
      c->add_option(
           "--subdivisions", a.subdivisions,
           "GCP local reconstruction: midpoint subdivisions of its mesh before projection onto "
           "the contact points (auto: 2 below 64 samples per axis, else 1)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option(
           "--split-sag", a.split_sag,
           "GCP local reconstruction, after the projection: split each edge once more where "
           "its chord sags by more than this many spacings (its length times its ends' "
           "normals' turn / 8) and project the new vertices; 0 or off: no split (auto: 0.002 "
           "from 64 to 95 samples per axis, else 0.004)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option(
           "--thin-parts", a.thin_parts,
           "GCP local reconstruction: find the parts thinner than a spacing that the "
           "samples straddle without a sign change (a wing, a blade) from the contact "
           "points on their two sides, on a grid of twice the resolution with one "
           "subdivision fewer (on, off; auto: on below 192 samples per axis, and from 192 to 256 "
           "where at least 0.25% of the edges that the surface crosses have such a gap next to "
           "them: two samples on one side, closer together than their values allow; with "
           "--edge-fans on: only when on, the fans then on the finer grid with about 4x their "
           "triangles)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--edge-fans", a.edge_fans,
                    "GCP local reconstruction: fan each grid edge's polygon from a vertex where "
                    "the surface crosses the edge, every vertex kept in its cell, edge or face, so "
                    "that the mesh cannot cross itself or leave a sample on the wrong side without "
                    "any repair (about 2-3.5x marching cubes' triangles; no subdivision, side "
                    "rounds or untangling; on, off; auto: on from 384 samples per axis, where it "
                    "takes about 0.4x the time for 1.4x the L1)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--local-reach", a.local.reach,
                    "GCP local reconstruction: contact points within this many spacings of a cell "
                    "feed its vertex")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--local-feature-ratio", a.local.feature_ratio,
                    "GCP local reconstruction: a cell's planes make an edge or corner where the "
                    "quadric's smaller eigenvalues exceed this fraction of its largest")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--local-robust-rounds", a.local_robust_rounds,
                    "GCP local reconstruction: reweighting rounds that discount planes missing the "
                    "vertex (auto: 3, none with edge fans on the grid itself)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--local-min-points", a.local.min_points,
                    "GCP local reconstruction: a cell with fewer contact points places its vertex "
                    "from its edge crossings")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--local-max-field-miss", a.local.max_field_miss,
                    "GCP local reconstruction: a vertex farther than this many spacings from the "
                    "cell's interpolated zero set falls back to the edge crossings (0: no check)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--local-depth-scale", a.local.depth_scale,
                    "GCP local reconstruction: a contact point from a sample |value| away weighs "
                    "1 / (1 + (|value| / (this many spacings))^2), in the cell quadrics and the "
                    "projection (0: all alike)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option(
           "--zero-set", a.zero_set,
           "GCP local reconstruction: move the vertices onto the zero set of the grid's "
           "tricubic interpolant, uncarved (auto: where the values are no exact distances, "
           "as a neural SDF's; on; off)")
          ->capture_default_str());
  a.local_options.push_back(
      c->add_option("--zero-set-mismatch", a.zero_set_mismatch,
                    "GCP --zero-set: only the vertices whose samples 1-2.5 spacings from the mesh "
                    "have a mean | |value| / distance - 1 | above this (0: every vertex)")
          ->capture_default_str());
}

// The projection onto the contact points and the sign constraints' options.
void add_projection_options(CLI::App* c, ContourArgs& a) {
  c->add_option("--projection", a.projection,
                "GCP: move each vertex along its normal onto a quadric fitted to the contact "
                "points within --projection-radius spacings whose normals agree with it (on, off; "
                "auto: on)")
      ->capture_default_str();
  // (The local reconstruction fits its own neighbourhoods: these tune the Poisson path's.)
  for (const ProjectionOption& p : kProjectionOptions)
    a.poisson_path_options.push_back(
        c->add_option(p.name, a.projection_options.*p.field, p.help)->capture_default_str());
  const std::pair<const char*, double*> sign_options[] = {{"--sign-band", &a.sign_band},
                                                          {"--sign-radius", &a.sign_radius},
                                                          {"--sign-margin", &a.sign_margin},
                                                          {"--sign-trigger", &a.sign_trigger}};
  const char* sign_help[] = {
      "GCP: samples within this many spacings of the surface keep their side",
      "GCP: a correction is a smooth bump of this many spacings around the sample",
      "GCP: and lie at least this fraction of their distance inside (outside) the mesh, as the "
      "indicator's slope there measures it",
      "GCP: a sample is corrected once it keeps less than this fraction of that margin (0: only "
      "samples on the wrong side)"};
  for (int i = 0; i < 4; ++i)
    a.poisson_path_options.push_back(
        c->add_option(sign_options[i].first, *sign_options[i].second, sign_help[i])
            ->capture_default_str());
}

// Reading the input: the .vdb grid, truncation, margin, bricks, --fn, --seed.
void add_input_options(CLI::App* c, ContourArgs& a) {
  c->add_option("--grid", a.grid,
                "For a .vdb input: the float level set grid to read (default: the first)");
  c->add_option("--margin", a.margin,
                "Samples up to this many spacings beyond the band are triangulated but give "
                "no contact point: they close the band's stars")
      ->capture_default_str();
  c->add_option("--truncation", a.truncation,
                "Values clamped at +-T carry no distance and are left out: T, 'none', or "
                "'auto' (a sign is truncated at its largest |value| when >= 64 samples, and "
                ">= 1% of that sign's samples, sit there)")
      ->capture_default_str();
  c->add_option(
       "--brick-size", a.brick_size,
       "GCP triangulates the band in bricks of this many spacings, each with a halo, "
       "in parallel; memory follows a brick, the result equals one global "
       "triangulation's; 0 triangulates the whole band at once (so does --band all); "
       "'auto': the largest of 256 down to 96 that makes >= 4 bricks per thread of <= 1.5M "
       "samples each, else 64. The local reconstruction runs in bricks of this many cells "
       "(auto: one brick up to 512 samples per axis, bricks of 512 beyond; with --edge-fans on, "
       "bricks of 256)")
      ->capture_default_str();
  c->add_option("--brick-halo", a.brick_halo,
                "First halo around a brick, in spacings (grown where it does not suffice); "
                "0: the largest |value| in the band and its margin, plus 2")
      ->capture_default_str();
  // (The local reconstruction slides a discarded point over its sphere instead.)
  a.poisson_path_options.push_back(
      c->add_flag("--fn", a.fn,
                  "+FN: if the averaged gradient's point is discarded, try each incident tet's "
                  "gradient (the paper's contact points, on the Poisson path)"));
  c->add_option("--seed", a.seed, "Seed for builtin:NAME@random:COUNT")->capture_default_str();
}

// The tuning knobs' group, which --help leaves out and --help-all lists. (CLI11 2.1's hidden
// group, "", also stops counting its options as given: their warnings would go.)
constexpr const char* kTuning = "Tuning";

class LevelsFormatter : public CLI::Formatter {
 public:
  std::string make_group(std::string group, bool is_positional,
                         std::vector<const CLI::Option*> opts) const override {
    if (group == kTuning && !show_all_options) return "";
    return CLI::Formatter::make_group(std::move(group), is_positional, std::move(opts));
  }
};

// The options a user decides (contour_option_names); the rest are tuning knobs, listed by
// --help-all. An option the table lacks, or a table entry the command lacks, is a bug here.
void group_by_level(CLI::App* c) {
  std::map<std::string, bool> user;
  for (const OptionName& o : contour_option_names())
    if (*o.cli) user[o.cli] = o.user;
  std::set<std::string> declared;
  for (CLI::Option* o : c->get_options()) {
    const std::vector<std::string>& names = o->get_lnames();
    if (names.empty()) continue;  // the input, positional
    const auto found = user.find(names.front());
    if (found == user.end())
      throw InternalError("contour option --" + names.front() + " is not in contour_option_names");
    declared.insert(names.front());
    if (!found->second) o->group(kTuning);
  }
  for (const auto& entry : user)
    if (!declared.count(entry.first))
      throw InternalError("contour_option_names lists --" + entry.first + ", which contour lacks");
}

// One sentence each for the options a user decides (the long accounts stay in --help-all's
// tuning group and in the docs).
void shorten_user_help(CLI::App* c) {
  const std::pair<const char*, const char*> short_help[] = {
      {"--band",
       "GCP uses the samples within this many spacings of the surface ('auto', or 'all')"},
      {"--reconstruction",
       "GCP's mesh: 'local' (per cell, brick by brick), 'poisson' (the paper's), or 'auto' "
       "(local for grids and .vdb, poisson for scattered samples)"},
      {"--truncation", "Values clamped at +-T carry no distance: T, 'none' or 'auto' (detected)"},
      {"--adaptivity",
       "Merge flat regions while the error stays under this many spacings (0: no merging)"}};
  for (const auto& [name, text] : short_help) c->get_option(name)->description(text);
}

}  // namespace

void add_contour_flags(CLI::App* c, ContourArgs& a) {
  c->add_option(
       "input", a.input,
       "A grid .npy (nx,ny,nz), scattered samples .npy (n,4: x,y,z,value), an OpenVDB level "
       "set .vdb, or builtin:NAME@N / builtin:NAME@random:COUNT (NAME: sphere, torus, box, "
       "plate, shell, csg)")
      ->required();
  c->add_option("-o,--output", a.output,
                "Mesh to write (.ply binary by default, .obj, .off or binary .stl)");
  c->add_option(
      "--points", a.points,
      "Contact points to write as PLY (x y z nx ny nz): GCP's, or GTCP's for --method gtcp");
  c->add_option("-m,--method", a.method, "gcp, gtcp, mc, mt-rt or mt-dt")->capture_default_str();
  c->add_option("--bounds", a.bounds,
                "Grid bounds (positions of the first and last samples) MIN,MAX or "
                "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX; also the box for random built-in samples")
      ->capture_default_str();
  add_contact_point_options(c, a);
  add_carving_options(c, a);
  add_reconstruction_options(c, a);
  add_projection_options(c, a);
  add_input_options(c, a);
  a.run.add_to(
      c, "Write a JSON summary (counts, per-stage seconds, contact point errors for built-ins)");
  c->add_flag("--serial-triangulation", a.serial_triangulation,
              "Insert points sequentially (same result, slower)");
  a.poisson.add_to(c);
  c->add_flag("--help-all",
              "List the tuning options too (gradients, bricks, signs, carving, "
              "projection, the local cells, the Poisson solver)");
  if (!show_all_options) shorten_user_help(c);
  group_by_level(c);
  c->formatter(std::make_shared<LevelsFormatter>());
  c->footer("Tuning options: sdfcontour contour --help-all");
}

}  // namespace sdfcontour::cli
