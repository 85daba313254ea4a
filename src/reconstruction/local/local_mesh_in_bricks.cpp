// A whole grid's local reconstruction from its bricks (local_brick.h): each brick's block read with
// a halo (copied out of a grid in memory, or read from a file: BlockedGrid), one brick after
// another (each parallel inside), the pieces joined by their vertices' keys.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <queue>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "pipeline/uninitialised_allocator.h"
#include "reconstruction/local/lattice_point_store.h"
#include "sdfcontour/contact_points/bricks.h"
#include "sdfcontour/reconstruction/local_brick.h"

namespace sdfcontour {

namespace {

using Index3 = std::array<int, 3>;

// Left unwritten when sized: the parallel copy into it faults its pages in (zeroed first, a
// brick's block of 308^3 floats took a fortieth of a second on one thread).
using detail::Unwritten;

// A block's storage, released once its brick has read it, stays for the next brick up to this
// many bytes (a brick of 256 with its halo is about 80 MB of floats): kept, the next block is not
// zeroed and faulted in again (bunny 512^3 in bricks of 256: 0.3-0.5 s less system time).
constexpr std::size_t kKeepBlockUpTo = std::size_t(256) << 20;

template <class Vector>
void release_if_large(Vector& values) {
  if (values.capacity() * sizeof(typename Vector::value_type) > kKeepBlockUpTo)
    Vector().swap(values);
}

// The block of `grid` with global samples [lo, hi), copied out in the grid's own type T (`values`
// keeps them; float32 grids stay float32, half the memory of a brick of doubles).
template <class T>
GridView copy_block(const GridView& grid, const Index3& lo, const Index3& hi,
                    Unwritten<T>& values) {
  GridView block;
  block.bounds = grid.bounds;
  block.first = lo;
  block.whole = grid.dims;
  for (std::size_t a = 0; a < 3; ++a) block.dims[a] = hi[a] - lo[a];
  block.type = std::is_same_v<T, float> ? ScalarType::Float32 : ScalarType::Float64;
  if (grid.type != block.type) throw InternalError("a block is copied in its grid's own type");
  values.resize(block.size());
  const std::size_t plane = std::size_t(block.dims[1]) * std::size_t(block.dims[2]);
  tbb::parallel_for(lo[0], hi[0], [&](int i) {
    std::size_t at = std::size_t(i - lo[0]) * plane;
    const std::size_t row = std::size_t(hi[2] - lo[2]);
    // (Row by row: element by element through value(), bricks of 64 at 512^3 spent a thirtieth
    // of their run copying.)
    for (int j = lo[1]; j < hi[1]; ++j, at += row)
      std::memcpy(&values[at], static_cast<const T*>(grid.data) + grid.index(i, j, lo[2]),
                  row * sizeof(T));
    // A file-mapped grid's pages go slab by slab, not after the whole block: mapped and copied
    // at once, a block of 567^3 floats was 1.46 GB (bunny 1024^3's peak).
    if (grid.drop_pages) {
      const std::size_t first = grid.index(i, lo[1], lo[2]),
                        last = grid.index(i, hi[1] - 1, hi[2] - 1);
      (*grid.drop_pages)(static_cast<const T*>(grid.data) + first, (last - first + 1) * sizeof(T));
    }
  });
  block.data = values.data();
  block.values_checked = true;  // (local_mesh_in_bricks validated the whole grid's values)
  return block;
}

}  // namespace

LocalPiece local_brick_piece(const BlockSource& source, const Index3& own_first,
                             const Index3& own_end, const LocalBrickOptions& options, int* wider) {
  if (!source.read) throw Error("a brick's grid needs its reader");
  int halo = local_brick_halo(options, source.dims);
  for (;;) {
    Index3 lo, hi;
    bool whole = true;
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = std::max(own_first[a] - halo, 0);
      hi[a] = std::min(own_end[a] + halo, source.dims[a]);
      whole = whole && lo[a] == 0 && hi[a] == source.dims[a];
    }
    try {
      if (whole && source.whole)
        return local_brick_piece(*source.whole, own_first, own_end, options);
      const GridView block = source.read(lo, hi);
      if (options.grid_read) options.grid_read();
      // The block goes as soon as the brick has read what it needs of it.
      LocalBrickOptions inner = options;
      inner.grid_read = source.release;
      return local_brick_piece(block, own_first, own_end, inner);
    } catch (const HaloTooSmall&) {
      if (whole) throw InternalError("a block holding the whole grid reported too small a halo");
      halo *= 2;
      if (wider) ++*wider;
    }
  }
}

namespace {

// Calls visit(list, row) for every entry of the ascending `lists` whose rows lie in [from[l],
// to[l]), in ascending (value, list) order: a k-way merge, so joining needs no sorted copy.
template <class Key, class Visit>
void merge_ascending(const std::vector<const std::vector<Key>*>& lists,
                     const std::vector<std::size_t>& from, const std::vector<std::size_t>& to,
                     Visit visit) {
  using Head = std::pair<Key, std::size_t>;
  std::priority_queue<Head, std::vector<Head>, std::greater<Head>> heads;
  std::vector<std::size_t> next = from;
  for (std::size_t l = 0; l < lists.size(); ++l)
    if (next[l] < to[l]) heads.push({(*lists[l])[next[l]], l});
  while (!heads.empty()) {
    const std::size_t l = heads.top().second;
    heads.pop();
    visit(l, next[l]);
    if (++next[l] < to[l]) heads.push({(*lists[l])[next[l]], l});
  }
}

// The ascending `lists` cut into key ranges that merge independently (in parallel): part q holds
// rows [cuts[q][l], cuts[q + 1][l]) of list l, and equal keys fall in one part. The cuts come
// from every list's quantiles weighed by its length, so the parts are about equally long wherever
// each list's keys lie (a brick's keys span only its own slab of the grid).
template <class Key>
std::vector<std::vector<std::size_t>> merge_parts(
    const std::vector<const std::vector<Key>*>& lists) {
  std::size_t total = 0;
  for (const auto* list : lists) total += list->size();
  constexpr std::size_t kPartLength = 1 << 12;
  const std::size_t parts = std::clamp<std::size_t>(total / kPartLength, 1, 256);
  // Each list's parts-quantiles stand for size / parts of its entries each.
  std::vector<std::pair<Key, std::size_t>> samples;
  for (const auto* list : lists)
    for (std::size_t q = 1; q < parts && !list->empty(); ++q)
      samples.emplace_back((*list)[list->size() * q / parts], list->size());
  std::sort(samples.begin(), samples.end());
  std::vector<std::vector<std::size_t>> cuts;
  cuts.emplace_back(lists.size(), 0);
  std::size_t weight = 0, next = 1;
  for (const auto& [at, size] : samples) {
    weight += size;  // in units of 1 / parts entries
    if (weight < total * next) continue;
    while (next < parts && weight >= total * next) ++next;
    std::vector<std::size_t> cut(lists.size());
    for (std::size_t l = 0; l < lists.size(); ++l)
      cut[l] =
          std::size_t(std::lower_bound(lists[l]->begin(), lists[l]->end(), at) - lists[l]->begin());
    if (cut != cuts.back()) cuts.push_back(std::move(cut));
  }
  std::vector<std::size_t> end(lists.size());
  for (std::size_t l = 0; l < lists.size(); ++l) end[l] = lists[l]->size();
  if (cuts.size() == 1 || end != cuts.back()) cuts.push_back(std::move(end));
  return cuts;
}

// join_local_pieces; with `owned` (the same pieces), each piece's arrays are freed once read, so
// the join holds little beyond the output mesh (23 M triangles at 1024³).
Mesh join_pieces(const std::vector<LocalPiece>& pieces, std::vector<LocalPiece>* owned) {
  // One piece is already in key and name order (LocalPiece): the merges below would copy it.
  if (pieces.size() == 1) {
    Mesh mesh;
    if (owned) {
      mesh.vertices = std::move((*owned)[0].vertices);
      mesh.triangles = std::move((*owned)[0].triangles);
      std::vector<VertexKey>().swap((*owned)[0].keys);
    } else {
      mesh.vertices = pieces[0].vertices;
      mesh.triangles = pieces[0].triangles;
    }
    return mesh;
  }
  std::vector<const std::vector<VertexKey>*> keys;
  std::vector<const std::vector<std::uint64_t>*> names;
  for (const LocalPiece& p : pieces) {
    keys.push_back(&p.keys);
    names.push_back(&p.triangle_names);
  }
  // Each key's vertex number, ascending; a key in several pieces is one vertex. Per part of the
  // keys: its distinct keys numbered from 0, then shifted by the parts before it.
  std::vector<std::vector<int>> id(pieces.size());
  for (std::size_t p = 0; p < pieces.size(); ++p) id[p].resize(pieces[p].keys.size());
  const std::vector<std::vector<std::size_t>> key_cuts = merge_parts(keys);
  const std::size_t key_parts = key_cuts.size() - 1;
  std::vector<int> distinct(key_parts, 0);
  tbb::parallel_for(std::size_t(0), key_parts, [&](std::size_t q) {
    int count = 0;
    bool first = true;
    VertexKey last{};
    merge_ascending(keys, key_cuts[q], key_cuts[q + 1], [&](std::size_t p, std::size_t row) {
      const VertexKey key = pieces[p].keys[row];
      if (first || key != last) ++count;
      first = false;
      last = key;
      id[p][row] = count - 1;
    });
    distinct[q] = count;
  });
  std::vector<int> base(key_parts + 1, 0);
  for (std::size_t q = 0; q < key_parts; ++q) base[q + 1] = base[q] + distinct[q];
  tbb::parallel_for(std::size_t(0), key_parts, [&](std::size_t q) {
    for (std::size_t p = 0; p < pieces.size(); ++p)
      for (std::size_t row = key_cuts[q][p]; row < key_cuts[q + 1][p]; ++row) id[p][row] += base[q];
  });
  const int vertices = base[key_parts];
  Mesh mesh;
  mesh.vertices.resize(vertices, 3);
  std::vector<char> placed(static_cast<std::size_t>(vertices), 0);
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    // (A piece's keys are distinct: its rows write distinct vertices.)
    const bool moved = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, pieces[p].keys.size()), false,
        [&](const tbb::blocked_range<std::size_t>& r, bool differs) {
          for (std::size_t row = r.begin(); row < r.end(); ++row) {
            const int v = id[p][row];
            const auto position = pieces[p].vertices.row(Eigen::Index(row));
            if (!placed[std::size_t(v)]) {
              mesh.vertices.row(v) = position;
              placed[std::size_t(v)] = 1;
            } else if (mesh.vertices.row(v) != position) {
              differs = true;
            }
          }
          return differs;
        },
        [](bool a, bool b) { return a || b; });
    if (moved) throw InternalError("two bricks placed one vertex differently");
    if (owned) {
      (*owned)[p].vertices = PointMatrix();
      std::vector<VertexKey>().swap((*owned)[p].keys);
    }
  }
  // The triangles in name order (names are distinct): each part's start is the rows before it.
  const std::vector<std::vector<std::size_t>> name_cuts = merge_parts(names);
  const std::size_t name_parts = name_cuts.size() - 1;
  std::vector<Eigen::Index> start(name_parts + 1, 0);
  for (std::size_t q = 0; q < name_parts; ++q) {
    start[q + 1] = start[q];
    for (std::size_t p = 0; p < pieces.size(); ++p)
      start[q + 1] += Eigen::Index(name_cuts[q + 1][p] - name_cuts[q][p]);
  }
  mesh.triangles.resize(start[name_parts], 3);
  tbb::parallel_for(std::size_t(0), name_parts, [&](std::size_t q) {
    Eigen::Index f = start[q];
    merge_ascending(names, name_cuts[q], name_cuts[q + 1], [&](std::size_t p, std::size_t t) {
      for (int c = 0; c < 3; ++c)
        mesh.triangles(f, c) = id[p][std::size_t(pieces[p].triangles(Eigen::Index(t), c))];
      ++f;
    });
  });
  return mesh;
}

}  // namespace

Mesh join_local_pieces(const std::vector<LocalPiece>& pieces) {
  return join_pieces(pieces, nullptr);
}

Mesh join_local_pieces(std::vector<LocalPiece>&& pieces) {
  Mesh mesh = join_pieces(pieces, &pieces);
  pieces.clear();
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

namespace {

// local_mesh_in_bricks of a grid `dims` across, read by `read`; bricks whose own samples grown by
// one cannot hold the surface (`may_hold_surface`, if set) are left out unread, and where `boxes`
// is set only the bricks that meet one of them are visited at all.
Mesh mesh_in_bricks(const BlockSource& source,
                    const std::function<bool(const Index3&, const Index3&)>& may_hold_surface,
                    const std::vector<SampleBox>* boxes, const LocalBrickOptions& given, int brick,
                    LocalBricksStats* stats, OrientedPoints* contact_points) {
  if (brick < 0) throw Error("the brick size must be positive (0: one brick)");
  const Index3& dims = source.dims;
  require_nameable(dims, given);
  // Each sample's lattice point made once, by the first brick that reads it.
  detail::LatticePointStore store;
  LocalBrickOptions options = given;
  options.lattice_store = &store;
  const int side = brick > 0 ? brick : *std::max_element(dims.begin(), dims.end());
  const std::vector<long> visit = bricks_meeting(dims, side, boxes, 1);
  const int total = int(visit.size());
  std::vector<LocalPiece> pieces(visit.size());
  std::vector<int> wider(visit.size(), 0);
  // One brick at a time, each parallel inside: memory is one brick's and the pieces' (bricks
  // in parallel held as many bricks as the scheduler started: 27 GB at 1024³ on 16 threads).
  for_each_listed_brick(dims, side, visit, [&](long b, const Index3& first, const Index3& end) {
    Index3 near_first, near_end;
    for (std::size_t a = 0; a < 3; ++a) {
      near_first[a] = std::max(first[a] - 1, 0);
      near_end[a] = std::min(end[a] + 1, dims[a]);
    }
    check_cancel(options.cancel);
    if (!may_hold_surface || may_hold_surface(near_first, near_end)) {
      pieces[std::size_t(b)] =
          local_brick_piece(source, first, end, options, &wider[std::size_t(b)]);
      if (source.release) source.release();  // (a brick without surface keeps its block)
      if (options.grid_read) options.grid_read();
      // (The freed memory stays for the next brick, of the same size: handed back to the system
      // after each brick, it came back as new pages the kernel zeroed. Bunny 1024^3 0.88x the
      // time at a peak of 1.04 GB instead of 0.86 GB; 512^3 0.90x at the same peak.)
    }
    if (options.progress) options.progress(int(b) + 1, total);
  });
  if (stats) {
    *stats = {};
    stats->thin_parts = local_thin_parts(options, dims);
    stats->lattice_points = !options.given_points && local_lattice_points(options, dims);
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
      s.thin_points += p.stats.thin_points;
      for (std::size_t k = 0; k < p.seconds.size(); ++k) stats->seconds[k] += p.seconds[k];
    }
  }
  if (contact_points) *contact_points = join_owned_contact_points(pieces);
  return join_local_pieces(std::move(pieces));
}

}  // namespace

Mesh local_mesh_in_bricks(const GridView& grid, const LocalBrickOptions& given, int brick,
                          LocalBricksStats* stats, OrientedPoints* contact_points) {
  validate_grid(grid);
  if (grid.whole[0] > 0 || grid.first != Index3{0, 0, 0})
    throw Error("local_mesh_in_bricks needs a whole grid, not a block");
  LocalBrickOptions options = given;
  if (options.band.truncation_mode == TruncationMode::Auto) {
    options.band.resolved = resolve_truncation(grid, options.band);
    options.band.truncation_mode = TruncationMode::Resolved;
  }
  Unwritten<float> floats;
  Unwritten<double> doubles;
  BlockSource source{grid.dims,
                     [&](const Index3& lo, const Index3& hi) {
                       return grid.type == ScalarType::Float32 ? copy_block(grid, lo, hi, floats)
                                                               : copy_block(grid, lo, hi, doubles);
                     },
                     [&] {
                       release_if_large(floats);
                       release_if_large(doubles);
                     },
                     &grid};
  return mesh_in_bricks(source, {}, nullptr, options, brick, stats, contact_points);
}

Mesh local_mesh_in_bricks(const BlockedGrid& grid, const LocalBrickOptions& options, int brick,
                          LocalBricksStats* stats, OrientedPoints* contact_points) {
  validate_grid_geometry(grid);
  if (!grid.read) throw Error("a grid read block by block needs its reader");
  if (options.band.truncation_mode == TruncationMode::Auto)
    throw Error("a grid read block by block needs its truncation resolved (none, given or found)");
  std::vector<float> floats;
  BlockSource source{
      grid.dims,
      [&](const Index3& lo, const Index3& hi) { return read_block(grid, lo, hi, floats); },
      [&] { release_if_large(floats); }, nullptr};
  return mesh_in_bricks(source, grid.may_hold_surface,
                        grid.surface_boxes ? &*grid.surface_boxes : nullptr, options, brick, stats,
                        contact_points);
}

}  // namespace sdfcontour
