// The Python binding: contouring arrays, sparse grids and .vdb level sets, with the other
// functions bound by file (binding/common.h). The friendly API is sdfcontour/__init__.py.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>

#include "binding/common.h"
#include "sdfcontour/io/vdb.h"
#include "sdfcontour/pipeline/option_ranges.h"

using namespace sdfcontour;
using namespace sdfcontour::binding;

namespace {

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

// A .vdb float level set, read sparse as the CLI reads it: (points (n, 3), values (n,), voxel
// size, background).
py::tuple run_read_vdb(const std::string& path, const std::string& grid_name) {
  VdbLevelSet level_set = run_interruptible(
      [path, grid_name](std::atomic<bool>&) { return read_vdb_level_set(path, grid_name); });
  return py::make_tuple(to_numpy(std::move(level_set.samples.points)),
                        to_numpy(std::move(level_set.samples.values)),  // (n, 1)
                        level_set.voxel_size, level_set.background);
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
  bind_bricks(m);
  bind_meshes(m);
}
