// The bricks that Dask runs and joins, and the single process's rules they share: each a call of
// the same C++ function the CLI's bricks run.
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>

#include "binding/common.h"
#include "reconstruction/local/lattice_point_store.h"
#include "sdfcontour/extraction/brick_marching.h"

namespace sdfcontour::binding {

namespace {

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

// One brick of GCP's local reconstruction (local_brick.h's local_brick_piece over a BlockSource):
// `read(first, dims)` returns the samples [first, first + dims) of a grid of `dims` over [lo, hi]
// as an array; the brick owns the edges from samples [own_first, own_end) and reads them with
// the core's halo, wider while its stars ask for more. `options` as contour()'s; `truncation`
// (inside, outside; inf: none) as found on the whole grid. `store` (or None): the lattice's
// contact points of the grid's earlier bricks, run one at a time in C order, as the core's bricks
// share them. Returns (keys (v, 2) uint64, vertices, triangles, stats). The GIL is released but
// while `read` runs.
py::tuple run_local_brick(const py::function& read, const std::array<int, 3>& dims,
                          const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                          const std::array<int, 3>& own_first, const std::array<int, 3>& own_end,
                          const py::dict& options, const std::array<double, 2>& truncation,
                          double value_scale, detail::LatticePointStore* store) {
  LocalBrickOptions lb =
      local_brick_options(with_edge_fans(contour_options(options), largest(dims)));
  lb.lattice_store = store;  // (read only where the points come from the lattice)
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

}  // namespace

void bind_bricks(py::module_& m) {
  m.def("marching_cubes_brick", &run_marching_cubes_brick, py::arg("block"), py::arg("first"),
        py::arg("dims"), py::arg("lo"), py::arg("hi"));
  m.def("local_brick", &run_local_brick, py::arg("read"), py::arg("dims"), py::arg("lo"),
        py::arg("hi"), py::arg("own_first"), py::arg("own_end"), py::arg("options"),
        py::arg("truncation"), py::arg("value_scale") = 1.0, py::arg("store").none(true) = nullptr);
  py::class_<detail::LatticePointStore>(
      m, "LatticeStore",
      "The lattice's contact points that a grid's bricks made, for local_brick's later bricks "
      "of the same grid (run one at a time, in C order): each sample's point made once.")
      .def(py::init<>());
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
}

}  // namespace sdfcontour::binding
