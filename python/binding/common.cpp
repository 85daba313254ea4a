// The binding's shared parts (common.h).
#include "binding/common.h"

#include <algorithm>
#include <iostream>
#include <limits>

#include "pipeline/progress_bar.h"
#include "sdfcontour/input/coordinates.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/pipeline/option_ranges.h"

namespace sdfcontour::binding {

void ProgressQueue::push(const std::string& stage, long done, long total) {
  std::lock_guard<std::mutex> lock(mutex);
  if (total > 0 && !events.empty() && std::get<0>(events.back()) == stage &&
      std::get<2>(events.back()) > 0)
    events.back() = {stage, done, total};
  else
    events.emplace_back(stage, done, total);
}

void ProgressQueue::deliver(const py::object& callback) {
  std::vector<std::tuple<std::string, long, long>> now;
  {
    std::lock_guard<std::mutex> lock(mutex);
    now.swap(events);
  }
  for (const auto& [stage, done, total] : now) callback(stage, done, total);
}

std::vector<std::pair<std::shared_ptr<Job>, py::object>>& abandoned_jobs() {
  static auto* jobs = new std::vector<std::pair<std::shared_ptr<Job>, py::object>>();
  return *jobs;
}

void release_finished_jobs() {
  auto& jobs = abandoned_jobs();
  jobs.erase(std::remove_if(jobs.begin(), jobs.end(),
                            [](auto& job) {
                              std::lock_guard<std::mutex> lock(job.first->mutex);
                              return job.first->done;
                            }),
             jobs.end());
}

// At exit, jobs still running are asked to stop and waited for.
void stop_abandoned_jobs() {
  for (auto& job : abandoned_jobs()) job.first->cancel = true;
  py::gil_scoped_release release;
  for (auto& job : abandoned_jobs()) job.first->wait(std::chrono::hours(1));
}

PointMatrix points_from(const DoubleArray& a, const char* what) {
  if (!a) throw Error(std::string(what) + " must be an array of numbers");
  if (a.ndim() != 2 || a.shape(1) != 3) throw Error(std::string(what) + " must have shape (n, 3)");
  PointMatrix m(a.shape(0), 3);
  std::copy(a.data(), a.data() + a.size(), m.data());
  require_coordinates(m, what);
  return m;
}

Mesh mesh_from(const py::array& V, const py::array& F) {
  Mesh mesh;
  mesh.vertices =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(V), "V");
  if (!(F.dtype().kind() == 'i' || F.dtype().kind() == 'u'))
    throw Error("F must be an array of whole numbers (vertex indices)");
  // Checked in 64 bits before narrowing, so an index of 2^32 + 1 is refused, not wrapped to 1.
  auto f = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(F);
  if (!f || f.ndim() != 2 || f.shape(1) != 3) throw Error("F must have shape (m, 3)");
  mesh.triangles.resize(f.shape(0), 3);
  for (py::ssize_t i = 0; i < f.size(); ++i) {
    const std::int64_t v = f.data()[i];
    if (v < 0 || v >= std::int64_t(mesh.vertices.rows()))
      throw Error("F indexes a vertex that V does not have");
    mesh.triangles.data()[i] = int(v);
  }
  return mesh;
}

PoissonOptions poisson_options(const py::dict& o) {
  PoissonOptions p;
  p.depth = get<int>(o, "depth", p.depth);
  p.full_depth = get<int>(o, "full_depth", p.full_depth);
  p.degree = get<int>(o, "degree", p.degree);
  p.refine_dilation = get<int>(o, "refine_dilation", p.refine_dilation);
  p.point_weight = get<double>(o, "alpha", p.point_weight);
  p.samples_per_node = get<double>(o, "samples_per_node", p.samples_per_node);
  p.scale = get<double>(o, "scale", p.scale);
  p.boundary = parse_poisson_boundary(get<std::string>(o, "boundary", "neumann"));
  p.solver_tolerance = get<double>(o, "solver_tolerance", p.solver_tolerance);
  p.finest_solver_tolerance = get<double>(o, "finest_solver_tolerance", p.finest_solver_tolerance);
  return p;
}

ContourOptions contour_options(const py::dict& o) {
  ContourOptions c;
  c.method = parse_method(get<std::string>(o, "method", "gcp"));
  c.gradient_source = parse_gradient_source(get<std::string>(o, "gradient", "auto"));
  c.gradient.weighting = parse_gradient_weighting(get<std::string>(o, "weights", "james"));
  c.knn = get<int>(o, "knn", c.knn);
  c.contact.try_tet_gradients = get<bool>(o, "fn", false);
  if (o.contains("tie_tolerance") && !o["tie_tolerance"].is_none())
    c.contact.tie_tolerance = c.lattice_tie_tolerance = o["tie_tolerance"].cast<double>();
  c.band.band = get<double>(o, "band", c.band.band);
  c.band.margin = get<double>(o, "margin", c.band.margin);
  const std::string truncation = get<std::string>(o, "truncation", "auto");
  if (truncation == "none") {
    c.band.truncation_mode = TruncationMode::None;
  } else if (truncation != "auto") {
    c.band.truncation_mode = TruncationMode::Given;
    const std::optional<double> given = parse_number(truncation);
    if (!given)
      throw Error("truncation must be 'auto', 'none' or a number, got '" + truncation + "'");
    c.band.truncation = *given;
  }
  c.bricks.size = get<int>(o, "brick_size", c.bricks.size);
  c.enforce_signs =
      parse_switch("sign_constraints", get<std::string>(o, "sign_constraints", "auto"));
  if (!get<bool>(o, "carve", true)) c.carve = Switch::Off;
  if (const int rounds = get<int>(o, "side_passes", -1); rounds >= 0) {
    c.carving.side_passes = rounds;
    c.carve_sides = rounds > 0 ? Switch::On : Switch::Off;
  }
  c.project = parse_switch("projection", get<std::string>(o, "projection", "auto"));
  c.zero_set = parse_switch("zero_set", get<std::string>(o, "zero_set", "auto"));
  c.thin_parts = parse_switch("thin_parts", get<std::string>(o, "thin_parts", "auto"));
  c.reconstruction = parse_reconstruction(get<std::string>(o, "reconstruction", "auto"));
  c.fallback_to_mc = get<bool>(o, "fallback_to_mc", c.fallback_to_mc);
  c.subdivisions = get<int>(o, "subdivisions", -1);
  c.split_sag = get<double>(o, "split_sag", -1.0);
  // (A brick's options from Dask's gcp_brick_piece may say True or False.)
  if (o.contains("edge_fans") && py::isinstance<py::bool_>(o["edge_fans"]))
    c.edge_fans = o["edge_fans"].cast<bool>() ? Switch::On : Switch::Off;
  else
    c.edge_fans = parse_switch("edge_fans", get<std::string>(o, "edge_fans", "auto"));
  c.adaptivity.tolerance = get<double>(o, "adaptivity", 0.0);
  c.bricks.halo = get<double>(o, "brick_halo", c.bricks.halo);
  c.poisson = poisson_options(o);
  if (get<std::string>(o, "depth_text", "") == "auto") c.poisson.depth = 0;
  if (get<std::string>(o, "refine_dilation_text", "") == "auto") c.poisson.refine_dilation = 0;
  if (get<bool>(o, "progress", false)) {
    c.progress = [](const std::string& m) { std::cerr << "[sdfcontour] " << m << std::endl; };
    c.progress_fraction = detail::ProgressBar();
    c.poisson.progress = c.progress;
  }
  return c;
}

Bounds bounds_of(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  Bounds bounds;
  bounds.min = Eigen::Vector3d(lo[0], lo[1], lo[2]);
  bounds.max = Eigen::Vector3d(hi[0], hi[1], hi[2]);
  return bounds;
}

SdfInput sdf_input(const py::array& array, const Bounds& bounds, double spacing, py::object& keep) {
  if (array.ndim() == 3) {
    GridInput grid;
    for (int a = 0; a < 3; ++a) {
      if (array.shape(a) > std::numeric_limits<int>::max())
        throw Error("the grid has " + std::to_string(array.shape(a)) +
                    " samples along an axis; at most 2147483647 are supported");
      grid.view.dims[a] = int(array.shape(a));
    }
    grid.view.bounds = bounds;
    const bool contiguous = array.flags() & py::array::c_style;
    if (contiguous && array.dtype().is(py::dtype::of<float>())) {
      grid.view.type = ScalarType::Float32;
      grid.view.data = array.data();
    } else if (contiguous && array.dtype().is(py::dtype::of<double>())) {
      grid.view.type = ScalarType::Float64;
      grid.view.data = array.data();
    } else {
      auto copy = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
      if (!copy) throw Error("the grid's values must be numbers");
      keep = copy;
      grid.view.type = ScalarType::Float64;
      grid.view.data = copy.data();
    }
    return grid;
  }
  if (array.ndim() == 2 && array.shape(1) == 4) {
    auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
    if (!a) throw Error("the samples must be numbers");
    ScatteredInput s;
    s.spacing = spacing;
    s.samples.points.resize(a.shape(0), 3);
    s.samples.values.resize(a.shape(0));
    for (py::ssize_t i = 0; i < a.shape(0); ++i) {
      for (int c = 0; c < 3; ++c) s.samples.points(i, c) = a.at(i, c);
      s.samples.values[i] = a.at(i, 3);
    }
    return s;
  }
  std::string shape = "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d)
    shape += (d ? ", " : "") + std::to_string(array.shape(d));
  throw Error("array of shape " + shape +
              ") is neither a grid (nx, ny, nz) nor scattered samples (n, 4)");
}

GridView block_view(const py::array& block, const std::array<int, 3>& first,
                    const std::array<int, 3>& dims, const std::array<double, 3>& lo,
                    const std::array<double, 3>& hi, py::object& keep) {
  if (block.ndim() != 3) throw Error("a block must be a 3D array");
  const SdfInput input = sdf_input(block, bounds_of(lo, hi), 0.0, keep);
  GridView view = *grid_view_of(input);
  view.first = first;
  view.whole = dims;
  return view;
}

double largest(const std::array<int, 3>& dims) {
  return double(*std::max_element(dims.begin(), dims.end()));
}

py::dict topology_stats(const Mesh& mesh) {
  const MeshTopology t = mesh_topology(mesh);
  py::dict out;
  out["closed"] = t.closed;
  out["oriented"] = t.consistently_oriented;
  out["manifold"] = t.nonmanifold_edges == 0;  // no edge with more than 2 triangles
  out["components"] = connected_components(mesh);
  return out;
}

py::dict adaptivity_stats(const AdaptivityStats& s) {
  py::dict a;
  a["triangles_before"] = s.triangles_before;
  a["triangles_after"] = s.triangles_after;
  a["merges"] = s.merges;
  a["freeze_rounds"] = s.freeze_rounds;
  a["fitted_vertices"] = s.fitted_vertices;
  return a;
}

}  // namespace sdfcontour::binding
