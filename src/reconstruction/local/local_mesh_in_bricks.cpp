// A whole grid's local reconstruction from its bricks (local_brick.h): each brick's block copied
// out with a halo, one brick after another (each parallel inside), the pieces joined by their
// vertices' keys.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <type_traits>

#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour {

namespace {

using Index3 = std::array<int, 3>;

// The block of `grid` with global samples [lo, hi), copied out in the grid's own type (`values`
// keeps them; float32 grids stay float32, half the memory of a brick of doubles).
template <class T>
GridView copy_block(const GridView& grid, const Index3& lo, const Index3& hi,
                    std::vector<T>& values) {
  GridView block;
  block.bounds = grid.bounds;
  block.first = lo;
  block.whole = grid.dims;
  for (std::size_t a = 0; a < 3; ++a) block.dims[a] = hi[a] - lo[a];
  values.resize(block.size());
  const std::size_t plane = std::size_t(block.dims[1]) * std::size_t(block.dims[2]);
  tbb::parallel_for(lo[0], hi[0], [&](int i) {
    std::size_t at = std::size_t(i - lo[0]) * plane;
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int k = lo[2]; k < hi[2]; ++k) values[at++] = T(grid.value(grid.index(i, j, k)));
  });
  block.data = values.data();
  block.type = std::is_same_v<T, float> ? ScalarType::Float32 : ScalarType::Float64;
  return block;
}

LocalPiece brick_piece(const GridView& grid, const Index3& own_first, const Index3& own_end,
                       const LocalBrickOptions& options, int& wider) {
  int halo = local_brick_halo(options, grid.dims);
  std::vector<float> floats;
  std::vector<double> doubles;
  for (;;) {
    Index3 lo, hi;
    bool whole = true;
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = std::max(own_first[a] - halo, 0);
      hi[a] = std::min(own_end[a] + halo, grid.dims[a]);
      whole = whole && lo[a] == 0 && hi[a] == grid.dims[a];
    }
    try {
      // A block that is the whole grid is the grid itself (no copy).
      if (whole) return local_brick_piece(grid, own_first, own_end, options);
      const GridView block = grid.type == ScalarType::Float32 ? copy_block(grid, lo, hi, floats)
                                                              : copy_block(grid, lo, hi, doubles);
      if (options.grid_read) options.grid_read();
      return local_brick_piece(block, own_first, own_end, options);
    } catch (const HaloTooSmall&) {
      if (whole) throw InternalError("a block holding the whole grid reported too small a halo");
      halo *= 2;
      ++wider;
    }
  }
}

}  // namespace

Mesh join_local_pieces(const std::vector<LocalPiece>& pieces) {
  struct Entry {
    VertexKey key;
    std::size_t piece;
    Eigen::Index row;
  };
  std::vector<Entry> entries;
  for (std::size_t p = 0; p < pieces.size(); ++p)
    for (std::size_t r = 0; r < pieces[p].keys.size(); ++r)
      entries.push_back({pieces[p].keys[r], p, Eigen::Index(r)});
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.key != b.key ? a.key < b.key : a.piece < b.piece;
  });
  std::vector<std::vector<int>> id(pieces.size());
  for (std::size_t p = 0; p < pieces.size(); ++p) id[p].resize(pieces[p].keys.size());
  Mesh mesh;
  std::vector<Eigen::Index> source_piece, source_row;
  int next = -1;
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const Entry& x = entries[e];
    if (e == 0 || x.key != entries[e - 1].key) {
      ++next;
      source_piece.push_back(Eigen::Index(x.piece));
      source_row.push_back(x.row);
    } else if (pieces[x.piece].vertices.row(x.row) !=
               pieces[std::size_t(source_piece.back())].vertices.row(source_row.back())) {
      throw InternalError("two bricks placed one vertex differently");
    }
    id[x.piece][std::size_t(x.row)] = next;
  }
  mesh.vertices.resize(next + 1, 3);
  for (int v = 0; v <= next; ++v)
    mesh.vertices.row(v) =
        pieces[std::size_t(source_piece[std::size_t(v)])].vertices.row(source_row[std::size_t(v)]);
  std::vector<std::tuple<std::uint64_t, std::size_t, Eigen::Index>> faces;
  for (std::size_t p = 0; p < pieces.size(); ++p)
    for (Eigen::Index t = 0; t < pieces[p].triangles.rows(); ++t)
      faces.emplace_back(pieces[p].triangle_names[std::size_t(t)], p, t);
  std::sort(faces.begin(), faces.end());
  mesh.triangles.resize(Eigen::Index(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const auto& [name, p, t] = faces[f];
    for (int c = 0; c < 3; ++c)
      mesh.triangles(Eigen::Index(f), c) = id[p][std::size_t(pieces[p].triangles(t, c))];
  }
  return mesh;
}

OrientedPoints join_owned_contact_points(const std::vector<LocalPiece>& pieces) {
  std::vector<std::tuple<std::uint64_t, std::size_t, Eigen::Index>> order;
  for (std::size_t p = 0; p < pieces.size(); ++p)
    for (std::size_t r = 0; r < pieces[p].owned_samples.size(); ++r)
      order.emplace_back(pieces[p].owned_samples[r], p, Eigen::Index(r));
  std::sort(order.begin(), order.end());
  OrientedPoints out;
  out.points.resize(Eigen::Index(order.size()), 3);
  out.normals.resize(Eigen::Index(order.size()), 3);
  for (std::size_t q = 0; q < order.size(); ++q) {
    const auto& [sample, p, r] = order[q];
    out.points.row(Eigen::Index(q)) = pieces[p].owned_points.row(r);
    out.normals.row(Eigen::Index(q)) = pieces[p].owned_normals.row(r);
  }
  return out;
}

Mesh local_mesh_in_bricks(const GridView& grid, const LocalBrickOptions& given, int brick,
                          LocalBricksStats* stats, OrientedPoints* contact_points) {
  validate_grid(grid);
  if (grid.whole[0] > 0 || grid.first != Index3{0, 0, 0})
    throw Error("local_mesh_in_bricks needs a whole grid, not a block");
  if (brick < 0) throw Error("the brick size must be positive (0: one brick)");
  LocalBrickOptions options = given;
  if (options.band.truncation_mode == TruncationMode::Auto) {
    options.band.resolved = resolve_truncation(grid, options.band);
    options.band.truncation_mode = TruncationMode::Resolved;
  }
  const int side = brick > 0 ? brick : *std::max_element(grid.dims.begin(), grid.dims.end());
  Index3 count;
  for (std::size_t a = 0; a < 3; ++a) count[a] = (grid.dims[a] + side - 1) / side;
  const int total = count[0] * count[1] * count[2];
  std::vector<LocalPiece> pieces(static_cast<std::size_t>(total));
  std::vector<int> wider(std::size_t(total), 0);
  // One brick at a time, each parallel inside: memory is one brick's and the pieces' (bricks
  // in parallel held as many bricks as the scheduler started: 27 GB at 1024³ on 16 threads).
  for (int b = 0; b < total; ++b) {
    const Index3 at{b / (count[1] * count[2]), b / count[2] % count[1], b % count[2]};
    Index3 first, end;
    for (std::size_t a = 0; a < 3; ++a) {
      first[a] = at[a] * side;
      end[a] = std::min(first[a] + side, grid.dims[a]);
    }
    check_cancel(options.cancel);
    pieces[std::size_t(b)] = brick_piece(grid, first, end, options, wider[std::size_t(b)]);
    if (options.grid_read) options.grid_read();
    if (options.progress) options.progress(b + 1, total);
  }
  if (stats) {
    *stats = {};
    for (std::size_t b = 0; b < pieces.size(); ++b) {
      const LocalPiece& p = pieces[b];
      stats->bricks += p.triangles.rows() > 0;
      stats->wider_halos += wider[b];
      stats->contact_points += p.contact_points;
      LocalReconstructionStats& s = stats->local;
      s.cells += p.stats.cells, s.vertices += p.stats.vertices;
      s.split_cells += p.stats.split_cells, s.crossing_cells += p.stats.crossing_cells;
      s.feature_vertices += p.stats.feature_vertices, s.clamped += p.stats.clamped;
      s.field_misses += p.stats.field_misses;
      for (std::size_t k = 0; k < p.seconds.size(); ++k) stats->seconds[k] += p.seconds[k];
    }
  }
  if (contact_points) *contact_points = join_owned_contact_points(pieces);
  return join_local_pieces(pieces);
}

}  // namespace sdfcontour
