// The Python binding: numpy arrays in (viewed in place where their layout allows), numpy arrays
// out (the C++ buffers handed over, not copied), the GIL released while C++ works, and Ctrl-C
// turned into a cancel request and a KeyboardInterrupt. The friendly API is sdfcontour/__init__.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <iostream>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <tuple>

#include "pipeline/progress_bar.h"
#include "sdfcontour/contact_points/contact_point_errors.h"
#include "sdfcontour/extraction/brick_marching.h"
#include "sdfcontour/input/coordinates.h"
#include "sdfcontour/input/mesh_sdf.h"
#include "sdfcontour/input/mesh_transform.h"
#include "sdfcontour/input/mesh_union.h"
#include "sdfcontour/input/signed_distance.h"
#include "sdfcontour/io/io.h"
#include "sdfcontour/io/vdb.h"
#include "sdfcontour/metrics/mesh_properties.h"
#include "sdfcontour/metrics/metrics.h"
#include "sdfcontour/pipeline/option_ranges.h"
#include "sdfcontour/pipeline/pipeline.h"

namespace py = pybind11;
using namespace sdfcontour;

namespace {

// A computation on its own thread: its cancel flag and whether it has finished.
struct Job {
  std::atomic<bool> cancel{false};
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  // Waits up to `timeout` for the job to finish; true if it has.
  bool wait(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex);
    return finished.wait_for(lock, timeout, [&] { return done; });
  }
};

// Progress events from the library's threads, handed to a Python callable on the calling thread
// (which holds the GIL) each time run_interruptible polls: (stage, done, total); total 0 for a
// stage's start message. Only the latest fraction of each stage is kept between polls.
struct ProgressQueue {
  std::mutex mutex;
  std::vector<std::tuple<std::string, long, long>> events;
  void push(const std::string& stage, long done, long total) {
    std::lock_guard<std::mutex> lock(mutex);
    if (total > 0 && !events.empty() && std::get<0>(events.back()) == stage &&
        std::get<2>(events.back()) > 0)
      events.back() = {stage, done, total};
    else
      events.emplace_back(stage, done, total);
  }
  // Calls `callback` for each event since the last call (GIL held by the caller).
  void deliver(const py::object& callback) {
    std::vector<std::tuple<std::string, long, long>> now;
    {
      std::lock_guard<std::mutex> lock(mutex);
      now.swap(events);
    }
    for (const auto& [stage, done, total] : now) callback(stage, done, total);
  }
};

// Jobs left running after a Ctrl-C, with the Python objects whose memory they still read. Those
// are released (GIL held) once the job has finished; never destroyed at exit without the GIL.
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

// Runs work(cancel) on a worker thread with the GIL released, polling for Ctrl-C every 50 ms.
// work must own everything it reads (it may outlive this call); `keep_alive` holds the Python
// objects whose memory it reads. On Ctrl-C the cancel flag is set (the library stops at its next
// stage, brick or solver iteration) and KeyboardInterrupt is raised at once: a worker that has
// not stopped within 0.2 s finishes in the background, its objects kept until then.
template <class Work>
auto run_interruptible(Work work, py::object keep_alive = py::none(),
                       const std::function<void()>& on_poll = {}) {
  using Result = decltype(work(std::declval<std::atomic<bool>&>()));
  release_finished_jobs();
  auto job = std::make_shared<Job>();
  auto result = std::make_shared<std::optional<Result>>();
  auto error = std::make_shared<std::exception_ptr>();
  std::thread([job, result, error, work = std::move(work)]() mutable {
    try {
      result->emplace(work(job->cancel));
    } catch (...) {
      *error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(job->mutex);
    job->done = true;
    job->finished.notify_all();
  }).detach();
  for (;;) {
    bool finished = false;
    {
      py::gil_scoped_release release;
      finished = job->wait(std::chrono::milliseconds(50));
    }
    if (on_poll) on_poll();  // with the GIL: the caller's Python progress callback
    if (finished) break;
    if (PyErr_CheckSignals() != 0) {
      py::error_already_set interrupt;  // the KeyboardInterrupt (or the handler's error)
      job->cancel = true;
      bool stopped = false;
      {
        py::gil_scoped_release release;
        stopped = job->wait(std::chrono::milliseconds(200));
      }
      if (!stopped) abandoned_jobs().push_back({job, std::move(keep_alive)});
      throw interrupt;
    }
  }
  if (*error) std::rethrow_exception(*error);
  return std::move(**result);
}

// A C++ matrix handed to numpy without a copy: numpy's array owns the moved matrix.
template <class Matrix>
py::array to_numpy(Matrix&& m) {
  using Scalar = typename std::decay_t<Matrix>::Scalar;
  auto* owned = new std::decay_t<Matrix>(std::forward<Matrix>(m));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::decay_t<Matrix>*>(p); });
  const py::ssize_t rows = owned->rows(), cols = owned->cols();
  return py::array_t<Scalar>({rows, cols},
                             {cols * py::ssize_t(sizeof(Scalar)), py::ssize_t(sizeof(Scalar))},
                             owned->data(), owner);
}

// The module's Python side has checked dtypes and shapes already; these checks stand guard for a
// direct call (a failed conversion is a null array, never dereferenced).
PointMatrix points_from(const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
                        const char* what) {
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

template <class T>
T get(const py::dict& options, const char* key, T fallback) {
  return options.contains(key) ? options[key].cast<T>() : fallback;
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

// The input as the library takes it: a 3D array is a grid over [lo, hi] viewed in place when it
// is C-contiguous float32 or float64 (else converted once); an (n, 4) array holds scattered
// samples. `keep` holds any converted copy.
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

// One brick of a larger grid by marching cubes (brick_marching.h): `block` holds the samples
// [first, first + block.shape) of a grid of `dims` samples over [lo, hi]. Returns the piece's
// global vertex keys (uint64, ascending), vertices and triangles; the GIL is released meanwhile
// so that a Dask worker's threads run bricks side by side.
py::tuple run_marching_cubes_brick(const py::array& block, const std::array<int, 3>& first,
                                   const std::array<int, 3>& dims, const std::array<double, 3>& lo,
                                   const std::array<double, 3>& hi) {
  if (block.ndim() != 3) throw Error("a brick must be a 3D array");
  GridGeometry grid;
  grid.dims = dims;
  grid.bounds = bounds_of(lo, hi);
  py::object keep;
  const SdfInput input = sdf_input(block, grid.bounds, 0.0, keep);
  const GridView view = *grid_view_of(input);
  MeshPiece piece;
  {
    py::gil_scoped_release release;
    piece = marching_cubes_brick(view, grid, first);
  }
  auto* keys = new std::vector<std::uint64_t>(std::move(piece.keys));
  py::capsule owner(keys, [](void* p) { delete static_cast<std::vector<std::uint64_t>*>(p); });
  py::array_t<std::uint64_t> key_array({py::ssize_t(keys->size())}, keys->data(), owner);
  return py::make_tuple(key_array, to_numpy(std::move(piece.vertices)),
                        to_numpy(std::move(piece.triangles)));
}

// A view of `block`, the samples [first, first + block.shape) of a grid of `dims` over [lo, hi]
// (`keep` holds a converted copy while the view is used).
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

// A grid's samples along its longest axis (what the automatic choices read).
double largest(const std::array<int, 3>& dims) {
  return double(*std::max_element(dims.begin(), dims.end()));
}

// One brick of GCP's local reconstruction (local_brick.h's local_brick_piece over a BlockSource):
// `read(first, dims)` returns the samples [first, first + dims) of a grid of `dims` over [lo, hi]
// as an array; the brick owns the edges from samples [own_first, own_end) and reads them with
// the core's halo, wider while its stars ask for more. `options` as contour()'s; `truncation`
// (inside, outside; inf: none) as found on the whole grid. Returns (keys (v, 2) uint64,
// vertices, triangles, stats). The GIL is released but while `read` runs.
py::tuple run_local_brick(const py::function& read, const std::array<int, 3>& dims,
                          const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                          const std::array<int, 3>& own_first, const std::array<int, 3>& own_end,
                          const py::dict& options, const std::array<double, 2>& truncation,
                          double value_scale) {
  LocalBrickOptions lb =
      local_brick_options(with_edge_fans(contour_options(options), largest(dims)));
  lb.band.truncation_mode = TruncationMode::Resolved;
  lb.band.resolved.inside = truncation[0];
  lb.band.resolved.outside = truncation[1];
  if (!(value_scale > 0) || !std::isfinite(value_scale))
    throw Error("value_scale must be positive and finite");
  lb.band.value_scale = value_scale;
  // Adaptivity merges the joined mesh over the contact points: the pieces hand theirs on.
  lb.keep_contact_points = lb.keep_contact_points || get<double>(options, "adaptivity", 0.0) > 0;
  // The last block read, and its converted copy where it needed one (released with the GIL).
  py::object block, keep;
  BlockSource source;
  source.dims = dims;
  source.read = [&](const std::array<int, 3>& first, const std::array<int, 3>& end) {
    py::gil_scoped_acquire acquire;
    block = read(py::make_tuple(first[0], first[1], first[2]),
                 py::make_tuple(end[0] - first[0], end[1] - first[1], end[2] - first[2]));
    const py::array array = py::array::ensure(block);
    if (!array) throw Error("a brick's read must return an array");
    std::string want, got;
    bool same = array.ndim() == 3;
    for (std::size_t a = 0; a < 3; ++a) want += (a ? ", " : "") + std::to_string(end[a] - first[a]);
    for (py::ssize_t a = 0; a < array.ndim(); ++a) {
      got += (a ? ", " : "") + std::to_string(array.shape(a));
      same = same && array.shape(a) == end[std::size_t(a)] - first[std::size_t(a)];
    }
    if (!same)
      throw Error("the grid's reader returned an array of shape (" + got + ") for a block of (" +
                  want + ")");
    return block_view(array, first, dims, lo, hi, keep);
  };
  source.release = [&] {
    py::gil_scoped_acquire acquire;
    block = keep = py::none();
  };
  LocalPiece piece;
  int wider = 0;
  {
    py::gil_scoped_release release;
    piece = local_brick_piece(source, own_first, own_end, lb, &wider);
  }
  py::array_t<std::uint64_t> keys({py::ssize_t(piece.keys.size()), py::ssize_t(2)});
  for (std::size_t v = 0; v < piece.keys.size(); ++v)
    for (int c = 0; c < 2; ++c) keys.mutable_at(py::ssize_t(v), c) = piece.keys[v][std::size_t(c)];
  py::dict stats;
  stats["contact_points"] = piece.contact_points;
  stats["wider_halos"] = wider;
  stats["local_cells"] = piece.stats.cells;
  stats["local_feature_vertices"] = piece.stats.feature_vertices;
  stats["local_field_misses"] = piece.stats.field_misses;
  stats["local_thin_points"] = piece.stats.thin_points;
  stats["local_crossing_cells"] = piece.stats.crossing_cells;
  py::array_t<std::uint64_t> names(py::ssize_t(piece.triangle_names.size()));
  std::copy(piece.triangle_names.begin(), piece.triangle_names.end(), names.mutable_data());
  stats["triangle_names"] = names;
  if (lb.keep_contact_points) {
    py::array_t<std::uint64_t> samples(py::ssize_t(piece.owned_samples.size()));
    std::copy(piece.owned_samples.begin(), piece.owned_samples.end(), samples.mutable_data());
    stats["owned_samples"] = samples;
    stats["owned_points"] = to_numpy(std::move(piece.owned_points));
    stats["owned_normals"] = to_numpy(std::move(piece.owned_normals));
  }
  return py::make_tuple(keys, to_numpy(std::move(piece.vertices)),
                        to_numpy(std::move(piece.triangles)), stats);
}

// The gradient norms next to sign changes (band.h's crossing_gradient_norms) at the samples
// [own_first, own_end) of a grid of `dims` over [lo, hi], from `block`, its samples [first,
// first + block.shape) (2 more on every side of the owned ones, where the grid has them).
py::tuple run_crossing_gradient_norms(const py::array& block, const std::array<int, 3>& first,
                                      const std::array<int, 3>& dims,
                                      const std::array<double, 3>& lo,
                                      const std::array<double, 3>& hi,
                                      const std::array<int, 3>& own_first,
                                      const std::array<int, 3>& own_end) {
  py::object keep;
  const GridView view = block_view(block, first, dims, lo, hi, keep);
  CrossingNorms norms;
  {
    py::gil_scoped_release release;
    norms = crossing_gradient_norms(view, {}, own_first, own_end);
  }
  auto array = [](const std::vector<double>& v) {
    py::array_t<double> out(py::ssize_t(v.size()));
    std::copy(v.begin(), v.end(), out.mutable_data());
    return out;
  };
  return py::make_tuple(array(norms.all), array(norms.kinkless));
}

// The subspacing gaps (subspacing_gaps.h) over the edges from the samples [own_first, own_end)
// of a grid of `dims` over [lo, hi], from `block`, its samples [first, first + block.shape) (one
// more before and two after the owned ones, where the grid has them): (gaps, crossings).
py::tuple run_subspacing_gaps(const py::array& block, const std::array<int, 3>& first,
                              const std::array<int, 3>& dims, const std::array<double, 3>& lo,
                              const std::array<double, 3>& hi, const std::array<int, 3>& own_first,
                              const std::array<int, 3>& own_end) {
  py::object keep;
  const GridView view = block_view(block, first, dims, lo, hi, keep);
  SubspacingGaps counts;
  {
    py::gil_scoped_release release;
    counts = count_subspacing_gaps(view, own_first, own_end);
  }
  return py::make_tuple(counts.gaps, counts.crossings);
}

using U64Array = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>;

// A brick's piece as the joins read it, (keys, V, F[, names]): its keys (`width` uint64 per
// vertex, ascending and distinct), V (v, 3) into `vertices` and F (f, 3) into `triangles`;
// `keys` and `names` (when the piece has them) stay as given.
void read_piece(const py::tuple& g, std::size_t width, const char* form, U64Array& keys,
                U64Array& names, PointMatrix& vertices, TriangleMatrix& triangles) {
  using I64 = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  using F64 = py::array_t<double, py::array::c_style | py::array::forcecast>;
  const bool named = width == 2;
  if (g.size() != (named ? 4 : 3)) throw Error(std::string("a piece is ") + form);
  keys = U64Array::ensure(g[0]);
  const I64 F = I64::ensure(g[2]);
  if (named) names = U64Array::ensure(g[3]);
  if (!keys || !F || (named && !names))
    throw Error("a piece's keys, triangles and names must be integers");
  const py::ssize_t v = keys.size() / py::ssize_t(width), f = F.size() / 3;
  if (keys.size() != py::ssize_t(width) * v || F.size() != 3 * f || (named && names.size() != f))
    throw Error(std::string("a piece must be ") + form + " with a row of V per key and " +
                "triangles (f, 3)");
  for (py::ssize_t i = 1; i < v; ++i)
    if (!std::lexicographical_compare(keys.data() + (i - 1) * width, keys.data() + i * width,
                                      keys.data() + i * width, keys.data() + (i + 1) * width))
      throw Error("a piece's keys must be ascending and distinct");
  vertices = v > 0 ? points_from(F64::ensure(g[1]), "a piece's V") : PointMatrix(0, 3);
  if (vertices.rows() != v) throw Error("a piece's V must have a row per key");
  triangles.resize(f, 3);
  for (py::ssize_t i = 0; i < 3 * f; ++i) {
    if (F.data()[i] < 0 || F.data()[i] >= v)
      throw Error("a piece's triangles must index its vertices");
    triangles.data()[i] = int(F.data()[i]);
  }
}

// Marching cubes' bricks' pieces (keys (v,) uint64 ascending, V (v, 3), F (f, 3) into V:
// marching_cubes_brick's) joined as the core joins them (join_mesh_pieces): vertices in key
// order, triangles in piece order. Returns (V, F).
py::tuple run_join_mesh_pieces(const std::vector<py::tuple>& given) {
  std::vector<MeshPiece> pieces(given.size());
  for (std::size_t b = 0; b < given.size(); ++b) {
    MeshPiece& p = pieces[b];
    U64Array keys, unnamed;
    read_piece(given[b], 1, "(keys, V, F)", keys, unnamed, p.vertices, p.triangles);
    p.keys.assign(keys.data(), keys.data() + keys.size());
  }
  Mesh mesh;
  {
    py::gil_scoped_release release;
    mesh = join_mesh_pieces(pieces);
  }
  return py::make_tuple(to_numpy(std::move(mesh.vertices)), to_numpy(std::move(mesh.triangles)));
}

// GCP's bricks' pieces (keys (v, 2) uint64 ascending, V (v, 3), F (f, 3) into V, the triangles'
// names (f,) uint64 ascending: local_brick's) joined as the core joins its bricks
// (join_local_pieces): vertices in key order, triangles in name order, the one-brick arrays
// whatever the bricks. Returns (V, F).
py::tuple run_join_local_pieces(const std::vector<py::tuple>& given) {
  std::vector<LocalPiece> pieces(given.size());
  for (std::size_t b = 0; b < given.size(); ++b) {
    LocalPiece& p = pieces[b];
    U64Array keys, names;
    read_piece(given[b], 2, "(keys (v, 2), V, F, triangle names)", keys, names, p.vertices,
               p.triangles);
    p.keys.resize(std::size_t(keys.size() / 2));
    for (std::size_t i = 0; i < p.keys.size(); ++i)
      p.keys[i] = {keys.data()[2 * i], keys.data()[2 * i + 1]};
    p.triangle_names.assign(names.data(), names.data() + names.size());
    if (!std::is_sorted(p.triangle_names.begin(), p.triangle_names.end()))
      throw Error("a piece's triangle names must be ascending");
  }
  Mesh mesh;
  {
    py::gil_scoped_release release;
    mesh = join_local_pieces(std::move(pieces));
  }
  return py::make_tuple(to_numpy(std::move(mesh.vertices)), to_numpy(std::move(mesh.triangles)));
}

// detect_truncation's counts (band.h) over a part of a grid, `block` (each sample in one part):
// (most negative, most positive, at the most negative, at the most positive, negatives, count).
py::tuple run_truncation_counts(const py::array& block) {
  py::object keep;
  const GridView view =
      block_view(block, {0, 0, 0}, {int(block.shape(0)), int(block.shape(1)), int(block.shape(2))},
                 {-1, -1, -1}, {1, 1, 1}, keep);
  TruncationCounts c;
  {
    py::gil_scoped_release release;
    c = truncation_counts(view);
  }
  return py::make_tuple(c.most_negative, c.most_positive, c.at_inside, c.at_outside, c.negatives,
                        c.count);
}

// The whole grid's truncation (inside, outside; inf: none) from its parts' counts, as
// detect_truncation decides on the whole.
std::pair<double, double> run_truncation_of_parts(const std::vector<py::tuple>& parts) {
  std::vector<TruncationCounts> counts;
  for (const py::tuple& p : parts) {
    if (p.size() != 6) throw Error("truncation counts are 6-tuples");
    counts.push_back({p[0].cast<double>(), p[1].cast<double>(), p[2].cast<long>(),
                      p[3].cast<long>(), p[4].cast<long>(), p[5].cast<long>()});
  }
  const Truncation t = truncation_of_parts(counts);
  return {t.inside, t.outside};
}

// A .vdb float level set, read sparse as the CLI reads it: (points (n, 3), values (n,), voxel
// size, background).
py::tuple run_read_vdb(const std::string& path, const std::string& grid_name) {
  VdbLevelSet level_set = run_interruptible(
      [path, grid_name](std::atomic<bool>&) { return read_vdb_level_set(path, grid_name); });
  return py::make_tuple(to_numpy(std::move(level_set.samples.points)),
                        to_numpy(std::move(level_set.samples.values)),  // (n, 1)
                        level_set.voxel_size, level_set.background);
}

// What the module's stats say of a mesh's topology.
py::dict topology_stats(const Mesh& mesh) {
  const MeshTopology t = mesh_topology(mesh);
  py::dict out;
  out["closed"] = t.closed;
  out["oriented"] = t.consistently_oriented;
  out["manifold"] = t.nonmanifold_edges == 0;  // no edge with more than 2 triangles
  out["components"] = connected_components(mesh);
  return out;
}

// What adaptivity did, as Python's stats["adaptivity"].
py::dict adaptivity_stats(const AdaptivityStats& s) {
  py::dict a;
  a["triangles_before"] = s.triangles_before;
  a["triangles_after"] = s.triangles_after;
  a["merges"] = s.merges;
  a["freeze_rounds"] = s.freeze_rounds;
  a["fitted_vertices"] = s.fitted_vertices;
  return a;
}

// contour() of `input` (whose memory `owners` keeps alive) as the module returns it.
py::dict contour_input(const SdfInput& input, const py::object& owners, const py::dict& options,
                       bool want_mesh, bool want_points, const py::object& progress_callback) {
  const GridView* view = grid_view_of(input);
  ContourOptions opt = contour_options(options);
  opt.want_mesh = want_mesh;
  opt.want_points = want_points;
  std::function<void()> deliver;
  if (!progress_callback.is_none()) {
    auto queue = std::make_shared<ProgressQueue>();
    opt.progress = [queue](const std::string& m) { queue->push(m, 0, 0); };
    opt.progress_fraction = [queue](const std::string& stage, long done, long total) {
      queue->push(stage, done, total);
    };
    opt.poisson.progress = opt.progress;
    deliver = [queue, progress_callback] { queue->deliver(progress_callback); };
  }
  ContourResult r = run_interruptible(
      [input, opt](std::atomic<bool>& cancel) mutable {
        opt.cancel = &cancel;
        return contour(input, opt);
      },
      owners, deliver);
  py::dict out;
  py::dict stats;
  if (r.mesh) {
    if (r.mesh->triangles.rows() == 0)
      throw Error("the " + method_name(opt.method) + " mesh is empty: no surface was found");
    stats.attr("update")(topology_stats(*r.mesh));
    out["V"] = to_numpy(std::move(r.mesh->vertices));
    out["F"] = to_numpy(std::move(r.mesh->triangles));
  }
  if (r.contact_points) {
    out["P"] = to_numpy(std::move(r.contact_points->points));
    out["N"] = to_numpy(std::move(r.contact_points->normals));
  }
  stats["samples"] = r.samples;
  stats["band_samples"] = r.band_samples;
  stats["isolated_samples"] = r.isolated_samples;
  stats["hidden_samples"] = r.hidden;
  stats["poisson_depth"] = r.poisson_depth;
  stats["value_scale"] = r.value_scale;
  if (!r.fallback.empty()) stats["fallback"] = r.fallback;
  stats["noise_level"] = r.noise_level;
  stats["smoothed"] = r.smoothed;
  stats["approximate_distances"] = r.approximate_distances;
  stats["pieces_removed"] = r.pieces_removed;
  stats["clipped_to_grid"] = r.clipped_to_grid;
  stats["sign_constraints"] = r.sign_constraints;
  stats["sign_violations"] = r.sign_violations;
  stats["sign_violations_left"] = r.sign_violations_left;
  stats["sign_constraints_dropped"] = r.sign_constraints_dropped;
  stats["carved_vertices"] = r.carving ? r.carving->vertices_moved : 0L;
  stats["projected_vertices"] = r.projection ? r.projection->vertices_moved : 0L;
  if (r.mesh) stats["reconstruction"] = reconstruction_name(r.reconstruction);
  if (r.local_bricks) {
    stats["local_bricks"] = r.local_bricks->bricks;
    stats["contact_points"] = r.local_bricks->contact_points;
    stats["local_thin_parts"] = r.local_bricks->thin_parts;
    stats["local_edge_fans"] = r.edge_fans;
  }
  if (r.subspacing_gaps) {
    stats["subspacing_gaps"] = r.subspacing_gaps->gaps;
    stats["crossing_edges"] = r.subspacing_gaps->crossings;
  }
  if (r.local) {
    stats["local_cells"] = r.local->cells;
    stats["local_feature_vertices"] = r.local->feature_vertices;
    stats["local_field_misses"] = r.local->field_misses;
    stats["local_thin_points"] = r.local->thin_points;
    stats["local_crossing_cells"] = r.local->crossing_cells;
  }
  stats["untangled_vertices"] = r.untangling ? r.untangling->vertices_reverted : 0;
  if (r.adaptivity) stats["adaptivity"] = adaptivity_stats(*r.adaptivity);
  stats["side_repaired_samples"] = r.side_repair ? r.side_repair->repaired : 0L;
  stats["wrong_side_left"] = r.side_repair ? r.side_repair->left : 0L;
  py::dict seconds;  // per stage, as the CLI's --stats "seconds" (repeated stages summed)
  for (const StageTime& t : r.stages)
    seconds[t.name.c_str()] =
        t.seconds + (seconds.contains(t.name) ? seconds[t.name.c_str()].cast<double>() : 0.0);
  stats["seconds"] = seconds;
  // Where the grid's values were read from: the caller's own buffer unless it had to be converted.
  if (view) stats["grid_address"] = std::uintptr_t(view->data);
  out["stats"] = stats;
  return out;
}

// contour() of a .vdb level set read box by box (vdb_blocked_grid): marching cubes or GCP's local
// reconstruction; its background is its truncation unless the options give one.
py::dict run_contour_vdb(const std::string& path, const std::string& grid_name,
                         const py::dict& options, const py::object& progress_callback) {
  BlockedGridInput input = run_interruptible([path, grid_name](std::atomic<bool>&) {
    VdbLayout layout;
    BlockedGrid grid = vdb_blocked_grid(path, grid_name, &layout);
    return BlockedGridInput{std::move(grid), layout.background, vdb_world_from_grid(layout)};
  });
  return contour_input(input, py::none(), options, true, false, progress_callback);
}

py::dict run_contour(const py::array& array, const std::array<double, 3>& lo,
                     const std::array<double, 3>& hi, double spacing, const py::dict& options,
                     bool want_mesh, bool want_points, const py::object& progress_callback) {
  py::object keep;
  const SdfInput input = sdf_input(array, bounds_of(lo, hi), spacing, keep);
  return contour_input(input, py::make_tuple(array, keep ? keep : py::object(py::none())), options,
                       want_mesh, want_points, progress_callback);
}

// contour() of a sparse grid: `blocks` a list of (brick index (3 ints), float64 array of the
// brick's samples and the next on each high side), `fill` (bricks per axis) the value of each
// brick not in the list (SparseGrid).
py::dict run_contour_sparse(const py::list& blocks, const py::array& fill, int brick,
                            const std::array<int, 3>& dims, const std::array<double, 3>& lo,
                            const std::array<double, 3>& hi, double value_scale,
                            double gradient_norm, const py::dict& options, bool want_mesh,
                            bool want_points, const py::object& progress_callback) {
  SparseGridInput input;
  SparseGrid& grid = input.grid;
  grid.dims = dims;
  grid.bounds = bounds_of(lo, hi);
  grid.brick = brick;
  if (brick < 1) throw Error("the sparse grid's bricks must be at least one cell wide");
  validate_grid_geometry(grid);
  for (int a = 0; a < 3; ++a) grid.bricks[a] = bricks_along(dims[a], brick);
  const auto f = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(fill);
  if (!f || f.ndim() != 3 || f.shape(0) != grid.bricks[0] || f.shape(1) != grid.bricks[1] ||
      f.shape(2) != grid.bricks[2])
    throw Error("the sparse grid's fill must hold one value per brick");
  grid.fill.assign(f.data(), f.data() + f.size());
  grid.block_of.assign(grid.fill.size(), -1);
  py::list owners;
  owners.append(f);
  for (const py::handle item : blocks) {
    const auto pair = item.cast<py::tuple>();
    const auto index = pair[0].cast<std::array<int, 3>>();
    const auto values =
        py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(pair[1]);
    if (!values || values.ndim() != 3) throw Error("a block of the sparse grid must be 3D");
    GridView block;
    for (int a = 0; a < 3; ++a) {
      if (index[a] < 0 || index[a] >= grid.bricks[a])
        throw Error("a block of the sparse grid lies outside it");
      block.dims[a] = int(values.shape(a));
      block.first[a] = index[a] * brick;
    }
    block.whole = dims;
    block.bounds = grid.bounds;
    block.data = values.data();
    const int b = (index[0] * grid.bricks[1] + index[1]) * grid.bricks[2] + index[2];
    if (grid.block_of[std::size_t(b)] >= 0)
      throw Error("a brick of the sparse grid is given twice");
    grid.block_of[std::size_t(b)] = int(grid.blocks.size());
    grid.blocks.push_back(block);
    owners.append(values);
  }
  input.value_scale = value_scale;
  input.gradient_norm = gradient_norm;
  return contour_input(input, owners, options, want_mesh, want_points, progress_callback);
}

// The mesh (V, F) merged where flat (adaptivity.h) over the contact points (P, N), `spacing` the
// grid's: (V, F, stats).
py::tuple run_adapt_mesh(const py::array& V, const py::array& F, const py::array& P,
                         const py::array& N, double spacing, double tolerance, int brick_spacings) {
  const Mesh mesh = mesh_from(V, F);
  const PointMatrix points =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(P), "P");
  const PointMatrix normals =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(N), "N");
  AdaptivityOptions options;  // (adapt_mesh checks the sizes, spacing and tolerance)
  options.tolerance = tolerance;
  options.brick_spacings = brick_spacings;
  AdaptivityStats stats;
  Mesh out = run_interruptible([&](std::atomic<bool>&) {
    return adapt_mesh(mesh, points, normals, spacing, options, &stats);
  });
  return py::make_tuple(to_numpy(std::move(out.vertices)), to_numpy(std::move(out.triangles)),
                        adaptivity_stats(stats));
}

py::tuple run_poisson(const py::array& P, const py::array& N, const py::object& W,
                      const py::dict& options) {
  OrientedPoints points;
  points.points =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(P), "P");
  points.normals =
      points_from(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(N), "N");
  if (!W.is_none()) {
    const auto w = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(W);
    if (!w || w.ndim() != 1 || w.shape(0) != points.points.rows())
      throw Error("W must have shape (n,), one weight per point");
    points.weights = Eigen::Map<const Eigen::VectorXd>(w.data(), w.shape(0));
  }
  PoissonOptions o = poisson_options(options);
  PoissonResult r = run_interruptible([points, o](std::atomic<bool>& cancel) mutable {
    o.cancel = &cancel;
    return poisson_reconstruct(points, o);
  });
  return py::make_tuple(to_numpy(std::move(r.mesh.vertices)),
                        to_numpy(std::move(r.mesh.triangles)));
}

// The grid of signed distances of a closed mesh, normalised first as the CLI's `sample` does
// when `scale` > 0 (longest side spanning [-scale, scale], centred); returns (grid, the mesh's
// vertices as sampled).
py::tuple run_sample(const py::array& V, const py::array& F, int resolution,
                     const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                     double scale) {
  if (resolution < 2 || resolution > 1024) throw Error("resolution must be between 2 and 1024");
  Mesh mesh = mesh_from(V, F);
  if (scale > 0) mesh = normalize_mesh(mesh, scale);
  const Bounds bounds = bounds_of(lo, hi);
  Grid grid = run_interruptible([mesh, resolution, bounds](std::atomic<bool>&) {
    require_closed_mesh(mesh, "the mesh");
    const MeshSdf sdf(union_of_overlapping_parts(mesh));
    return sample_grid(sdf, resolution, bounds);
  });
  auto* owned = new Eigen::VectorXd(std::move(grid.values));
  py::capsule owner(owned, [](void* p) { delete static_cast<Eigen::VectorXd*>(p); });
  const py::ssize_t n = resolution, d = sizeof(double);
  return py::make_tuple(py::array_t<double>({n, n, n}, {n * n * d, n * d, d}, owned->data(), owner),
                        to_numpy(std::move(mesh.vertices)));
}

py::dict run_distances(const py::array& V, const py::array& F, const py::array& V_gt,
                       const py::array& F_gt, std::size_t samples, std::uint64_t seed) {
  if (samples == 0 || samples > 100000000) throw Error("samples must be between 1 and 1e8");
  const Mesh recon = mesh_from(V, F), gt = mesh_from(V_gt, F_gt);
  const SurfaceDistances d = run_interruptible([recon, gt, samples, seed](std::atomic<bool>&) {
    return surface_distances(recon, gt, samples, seed);
  });
  const MeshTopology t = mesh_topology(recon);
  py::dict out;
  out["L1"] = d.l1;
  out["L2"] = d.l2;
  out["L_inf"] = d.hausdorff;
  out["recon_to_gt"] =
      py::dict(py::arg("mean") = d.mean_ab, py::arg("rms") = d.rms_ab, py::arg("max") = d.max_ab);
  out["gt_to_recon"] =
      py::dict(py::arg("mean") = d.mean_ba, py::arg("rms") = d.rms_ba, py::arg("max") = d.max_ba);
  out["closed"] = t.closed;
  out["components"] = connected_components(recon);
  return out;
}

py::tuple run_read_mesh(const std::string& path) {
  Mesh mesh = read_mesh(path);
  return py::make_tuple(to_numpy(std::move(mesh.vertices)), to_numpy(std::move(mesh.triangles)));
}

void run_write_mesh(const std::string& path, const py::array& V, const py::array& F, bool ascii) {
  write_mesh(path, mesh_from(V, F), ascii ? PlyFormat::Ascii : PlyFormat::Binary);
}

}  // namespace

PYBIND11_MODULE(_sdfcontour, m) {
  m.doc() = "C++ core of sdfcontour; use the functions of the sdfcontour package.";
  py::module_::import("atexit").attr("register")(py::cpp_function(&stop_abandoned_jobs));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const IoError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const Cancelled&) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
    } catch (const InternalError& e) {
      PyErr_SetString(PyExc_RuntimeError,
                      (std::string("internal error (please report it): ") + e.what()).c_str());
    } catch (const Error& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError, "out of memory (try a smaller band or brick size)");
    }
  });
  m.def(
      "parse_number",
      [](const std::string& text) -> py::object {
        const std::optional<double> x = parse_number(text);
        return x ? py::object(py::float_(*x)) : py::object(py::none());
      },
      py::arg("text"), "A number as text, read as the CLI reads it (None if it is none)");
  m.def("contour", &run_contour, py::arg("array"), py::arg("lo"), py::arg("hi"), py::arg("spacing"),
        py::arg("options"), py::arg("want_mesh"), py::arg("want_points"),
        py::arg("progress_callback") = py::none());
  m.def("contour_sparse", &run_contour_sparse, py::arg("blocks"), py::arg("fill"), py::arg("brick"),
        py::arg("dims"), py::arg("lo"), py::arg("hi"), py::arg("value_scale"),
        py::arg("gradient_norm"), py::arg("options"), py::arg("want_mesh"), py::arg("want_points"),
        py::arg("progress_callback") = py::none());
  m.def("marching_cubes_brick", &run_marching_cubes_brick, py::arg("block"), py::arg("first"),
        py::arg("dims"), py::arg("lo"), py::arg("hi"));
  m.def("local_brick", &run_local_brick, py::arg("read"), py::arg("dims"), py::arg("lo"),
        py::arg("hi"), py::arg("own_first"), py::arg("own_end"), py::arg("options"),
        py::arg("truncation"), py::arg("value_scale") = 1.0);
  m.attr("LOCAL_BRICK") = kLocalBrick;
  m.def("crossing_gradient_norms", &run_crossing_gradient_norms, py::arg("block"), py::arg("first"),
        py::arg("dims"), py::arg("lo"), py::arg("hi"), py::arg("own_first"), py::arg("own_end"));
  m.def(
      "edge_fans_chosen",
      [](const py::dict& options, const std::array<int, 3>& dims) {
        return with_edge_fans(contour_options(options), largest(dims)).local.edge_fans;
      },
      py::arg("options"), py::arg("dims"),
      "Whether the local reconstruction fans grid edges with these options on a grid of these "
      "dims (the single process's rule, with_edge_fans).");
  m.def("thin_parts_need_gaps", &thin_parts_need_gaps, py::arg("samples_per_axis"),
        "Whether the choice of thin parts needs the grid's subspacing gaps (the single "
        "process's rule; elsewhere auto_thin_parts(samples_per_axis, 0, 0) decides).");
  m.def("join_local_pieces", &run_join_local_pieces, py::arg("pieces"));
  m.def("join_mesh_pieces", &run_join_mesh_pieces, py::arg("pieces"));
  m.def("truncation_counts", &run_truncation_counts, py::arg("block"));
  m.def("truncation_of_parts", &run_truncation_of_parts, py::arg("parts"));
  m.def("subspacing_gaps", &run_subspacing_gaps, py::arg("block"), py::arg("first"),
        py::arg("dims"), py::arg("lo"), py::arg("hi"), py::arg("own_first"), py::arg("own_end"));
  m.def(
      "auto_thin_parts",
      [](double samples_per_axis, std::int64_t gaps, std::int64_t crossings) {
        return auto_thin_parts(samples_per_axis, SubspacingGaps{gaps, crossings});
      },
      py::arg("samples_per_axis"), py::arg("gaps"), py::arg("crossings"),
      "Whether GCP's local reconstruction looks for thin parts on a grid of this size with these "
      "subspacing gaps (the single process's rule).");
  m.def(
      "distance_value_scale",
      [](py::array_t<double, py::array::c_style | py::array::forcecast> all,
         py::array_t<double, py::array::c_style | py::array::forcecast> kinkless) {
        const GradientNormSummary s = summarize_gradient_norms(
            {std::vector<double>(all.data(), all.data() + all.size()),
             std::vector<double>(kinkless.data(), kinkless.data() + kinkless.size())});
        return py::make_tuple(distance_value_scale(s.slope), s.median);
      },
      py::arg("all"), py::arg("kinkless"),
      "(value_scale, median) of crossing_gradient_norms' two lists: the factor that makes the "
      "values distances.");
  m.def(
      "contour_values_reach",
      [](const py::dict& options, const std::array<int, 3>& dims) {
        return contour_values_reach(contour_options(options), dims);
      },
      py::arg("options"), py::arg("dims"));
  m.def(
      "local_values_reach",
      [](const py::dict& options, const std::array<int, 3>& dims) {
        return local_values_reach(
            local_brick_options(with_edge_fans(contour_options(options), largest(dims))), dims);
      },
      py::arg("options"), py::arg("dims"));
  m.def(
      "local_brick_halo",
      [](const py::dict& options, const std::array<int, 3>& dims) {
        return local_brick_halo(
            local_brick_options(with_edge_fans(contour_options(options), largest(dims))), dims);
      },
      py::arg("options"), py::arg("dims"));
  m.def(
      "mesh_topology",
      [](const py::array& V, const py::array& F) { return topology_stats(mesh_from(V, F)); },
      py::arg("V"), py::arg("F"));
  m.def(
      "vdb_layout",
      [](const std::string& path, const std::string& grid_name) {
        const VdbLayout l = run_interruptible(
            [path, grid_name](std::atomic<bool>&) { return read_vdb_layout(path, grid_name); });
        py::dict out;
        out["grid_name"] = l.grid_name;
        out["min"] = l.min;
        out["max"] = l.max;
        out["voxel_size"] = l.voxel_size;
        out["origin"] = std::array<double, 3>{l.origin[0], l.origin[1], l.origin[2]};
        py::array_t<double> rotation({py::ssize_t(3), py::ssize_t(3)});
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) rotation.mutable_at(a, b) = l.rotation(a, b);
        out["rotation"] = rotation;
        out["background"] = l.background;
        py::array_t<int> leaves({py::ssize_t(l.leaf_origins.size()), py::ssize_t(3)});
        for (std::size_t i = 0; i < l.leaf_origins.size(); ++i)
          for (int a = 0; a < 3; ++a) leaves.mutable_at(py::ssize_t(i), a) = l.leaf_origins[i][a];
        out["leaf_origins"] = leaves;
        return out;
      },
      py::arg("path"), py::arg("grid_name"));
  m.def(
      "read_vdb_box",
      [](const std::string& path, const std::string& grid_name, const std::array<int, 3>& first,
         const std::array<int, 3>& dims) {
        std::vector<float> values;
        {
          py::gil_scoped_release release;
          values = read_vdb_box(path, grid_name, first, dims);
        }
        py::array_t<float> out({py::ssize_t(dims[0]), py::ssize_t(dims[1]), py::ssize_t(dims[2])});
        std::copy(values.begin(), values.end(), out.mutable_data());
        return out;
      },
      py::arg("path"), py::arg("grid_name"), py::arg("first"), py::arg("dims"));
  m.def("read_vdb", &run_read_vdb, py::arg("path"), py::arg("grid_name"));
  m.def("contour_vdb", &run_contour_vdb, py::arg("path"), py::arg("grid_name"), py::arg("options"),
        py::arg("progress_callback") = py::none());
  m.def("read_mesh", &run_read_mesh, py::arg("path"));
  m.def("write_mesh", &run_write_mesh, py::arg("path"), py::arg("V"), py::arg("F"),
        py::arg("ascii"));
  m.def("adapt_mesh", &run_adapt_mesh, py::arg("V"), py::arg("F"), py::arg("P"), py::arg("N"),
        py::arg("spacing"), py::arg("tolerance"),
        py::arg("brick_spacings") = AdaptivityOptions{}.brick_spacings);
  m.def("poisson", &run_poisson, py::arg("P"), py::arg("N"), py::arg("W"), py::arg("options"));
  m.def("sample", &run_sample, py::arg("V"), py::arg("F"), py::arg("resolution"), py::arg("lo"),
        py::arg("hi"), py::arg("scale"));
  m.def("auto_band", &sdfcontour::auto_band, py::arg("samples_per_axis"));
  m.def("option_ranges", [] {
    py::dict ranges;  // Python keyword -> (lo, hi)
    for (const OptionRange& r : option_ranges())
      if (*r.python) ranges[r.python] = py::make_tuple(r.lo, r.hi);
    return ranges;
  });
  m.def("contour_option_names", [] {
    py::list names;  // (CLI name, Python keyword, decided by a user), contour_option_names
    for (const OptionName& o : contour_option_names())
      names.append(py::make_tuple(o.cli, o.python, o.user));
    return names;
  });
  m.def("distances", &run_distances, py::arg("V"), py::arg("F"), py::arg("V_gt"), py::arg("F_gt"),
        py::arg("samples"), py::arg("seed"));
}
