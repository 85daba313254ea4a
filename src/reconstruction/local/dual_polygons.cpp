// The dual mesh's polygons: one per sign-changing grid edge whose four cells are searched (inside
// the grid, or the cells' box), through the vertices of the four cells around it, with a vertex of
// its own for each segment of a face that two cells' polygons would otherwise share twice.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

#include "extraction/cube_polygons.h"
#include "reconstruction/local/surface_cells.h"

namespace sdfcontour::detail {

namespace {

// A segment vertex asked for by a polygon: its key (the face and the face corner that the
// segment cuts off) and position (the middle of the segment).
struct SegmentVertex {
  std::int64_t key = 0;
  Eigen::Vector3d position;
};

// Segment vertices are rare (ambiguous faces): a slot keeps them aside, so that a slot per cell
// and axis stays small.
struct PolygonSlot {
  std::array<int, 8> vertices{};  // -1: the next of `segments`, in order
  std::vector<SegmentVertex> segments;
  int size = 0;
  std::uint64_t edge = 0;  // the grid edge's global key
  Eigen::Vector3d edge_point;
};

Eigen::Vector3d crossing(const SurfaceCells& cells, const std::array<int, 3>& p, int axis) {
  std::array<int, 3> q = p;
  ++q[std::size_t(axis)];
  const double f0 = value_at(cells.grid, p), f1 = value_at(cells.grid, q);
  const double t = f0 / (f0 - f1);
  return cells.corner(p) + t * (cells.corner(q) - cells.corner(p));
}

// Cells x and y share the face perpendicular to `b` through grid point `edge_start`, spanning
// axis a (the edge) and axis w from edge_start[w] + w_offset. If both cells' polygons cross all
// four of the face's edges (with `every`: if the surface crosses all four), the face's two
// segments would join the same two vertices twice: returns the segment vertex of the segment
// that the edge (edge_start, a) ends on.
bool shared_twice(const SurfaceCells& cells, const ActiveCell& x, const ActiveCell& y,
                  const std::array<int, 3>& edge_start, int a, int b, int w, int w_offset,
                  bool every, SegmentVertex& out) {
  const CubeTables& T = cube_tables();
  std::array<int, 3> low = edge_start;
  low[std::size_t(w)] += w_offset;
  // The face's four edges in each cell: (low, a), (low + w, a), (low, w), (low + a, w), named by
  // their low corner relative to the cell.
  auto same_polygon = [&](const ActiveCell& cell) {
    const std::array<int, 3> at = cells.cell_of_key(cell.key);
    int polygon = -2;
    const int along[4][3] = {{0, 0, a}, {1, 0, a}, {0, 0, w}, {0, 1, w}};  // (+w, +a, axis)
    for (const auto& e : along) {
      int corner = 0;
      for (int d = 0; d < 3; ++d) {
        int p = low[std::size_t(d)] + (d == w ? e[0] : 0) + (d == a ? e[1] : 0);
        corner |= (p - at[std::size_t(d)]) << d;
      }
      const int q = cell.polygon_of_edge[std::size_t(T.edge_id[corner][e[2]])];
      if (q < 0 || (!every && polygon != -2 && q != polygon)) return false;
      polygon = q;
    }
    return true;
  };
  if (!same_polygon(x) || !same_polygon(y)) return false;
  // The corner cut off: the end of the edge whose sign is isolated on the face (outside where
  // the face's insides connect). x decides the face like y (cube_case).
  const std::array<int, 3> xat = cells.cell_of_key(x.key);
  const int side = low[std::size_t(b)] > xat[std::size_t(b)] ? 1 : 0;
  const bool connected = (x.connected >> (2 * b + side) & 1) != 0;
  std::array<int, 3> cut = edge_start;
  const bool start_inside = value_at(cells.grid, edge_start) < 0;
  if (start_inside == connected) ++cut[std::size_t(a)];  // the isolated sign is at the other end
  // Numbered by the face's own axes (not the edge's), so that all four polygons agree.
  const std::size_t b1 = std::size_t((b + 1) % 3), b2 = std::size_t((b + 2) % 3);
  const int corner_in_face = (cut[b1] - low[b1]) + 2 * (cut[b2] - low[b2]);
  const std::int64_t face_low = std::int64_t(cells.global_point(low));
  out.key = (face_low * 3 + b) * 4 + corner_in_face;
  std::array<int, 3> a_start = cut, w_start = cut;
  a_start[std::size_t(a)] = low[std::size_t(a)];
  w_start[std::size_t(w)] = low[std::size_t(w)];
  out.position = 0.5 * (crossing(cells, a_start, a) + crossing(cells, w_start, w));
  return true;
}

// The polygon of the edge from cell `at`'s lowest corner along axis a.
PolygonSlot edge_polygon(const SurfaceCells& cells, const ActiveCell& cell,
                         const std::array<int, 3>& at, int a, bool every) {
  const CubeTables& T = cube_tables();
  const int u = (a + 1) % 3, v = (a + 2) % 3;
  // The cells around the edge, counter-clockwise about +a, by their offsets in (u, v).
  const int offsets[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const ActiveCell* around[4];
  for (int q = 0; q < 4; ++q) {
    std::array<int, 3> n = at;
    n[std::size_t(u)] -= offsets[q][0];
    n[std::size_t(v)] -= offsets[q][1];
    around[q] = &cells.active[std::size_t(cells.find(cells.key(n)))];
  }
  PolygonSlot slot;
  slot.edge = 3 * cells.global_point(at) + std::uint64_t(a);
  slot.edge_point = crossing(cells, at, a);
  for (int q = 0; q < 4; ++q) {
    const int low = offsets[q][0] << u | offsets[q][1] << v;
    slot.vertices[std::size_t(slot.size++)] =
        around[q]->first_vertex + around[q]->polygon_of_edge[std::size_t(T.edge_id[low][a])];
    // Cells q and q + 1 differ along b; the face between them spans w from their shared offset.
    const int r = (q + 1) % 4;
    const bool differ_u = offsets[q][0] != offsets[r][0];
    const int b = differ_u ? u : v, w = differ_u ? v : u;
    const int w_offset = -(differ_u ? offsets[q][1] : offsets[q][0]);
    SegmentVertex sv;
    if (shared_twice(cells, *around[q], *around[r], at, a, b, w, w_offset, every, sv)) {
      slot.segments.push_back(sv);
      slot.vertices[std::size_t(slot.size++)] = -1;
    }
  }
  if (!(cell.inside & 1)) {  // outside at the low end: the surface faces -a
    std::reverse(slot.vertices.begin(), slot.vertices.begin() + slot.size);
    std::reverse(slot.segments.begin(), slot.segments.end());
  }
  return slot;
}

}  // namespace

DualPolygons SurfaceCells::dual_polygons(bool every_ambiguous_face) const {
  const CubeTables& T = cube_tables();
  // The slots in fixed parts of the cells, each made (and its pages first touched) by the thread
  // that fills it: one array for all, made up front, was most of this at 2 threads (bunny 256^3).
  constexpr std::size_t kPart = 4096;
  std::vector<std::vector<std::array<PolygonSlot, 3>>> parts((active.size() + kPart - 1) / kPart);
  tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t part) {
    const std::size_t first = part * kPart, end = std::min(active.size(), first + kPart);
    parts[part].resize(end - first);
    for (std::size_t c = first; c < end; ++c) {
      const ActiveCell& cell = active[c];
      const std::array<int, 3> at = cell_of_key(cell.key);
      for (int a = 0; a < 3; ++a) {
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        // (The four cells around the edge: this one and those below it in u and v.)
        if (cell.polygon_of_edge[std::size_t(T.edge_id[0][a])] < 0 ||
            at[std::size_t(u)] <= box_lo[std::size_t(u)] ||
            at[std::size_t(v)] <= box_lo[std::size_t(v)])
          continue;
        parts[part][c - first][std::size_t(a)] =
            edge_polygon(*this, cell, at, a, every_ambiguous_face);
      }
    }
  });
  // Segment vertices, numbered by key after the cells' vertices.
  std::vector<std::pair<std::int64_t, Eigen::Vector3d>> segments;
  for (const auto& slots : parts)
    for (const auto& s3 : slots)
      for (const PolygonSlot& s : s3)
        for (const SegmentVertex& sv : s.segments) segments.push_back({sv.key, sv.position});
  std::sort(segments.begin(), segments.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  segments.erase(std::unique(segments.begin(), segments.end(),
                             [](const auto& x, const auto& y) { return x.first == y.first; }),
                 segments.end());
  DualPolygons out;
  for (const auto& s : segments) {
    out.extra_keys.push_back(std::uint64_t(s.first));
    out.extra_positions.push_back(s.second);
  }
  // Each part's polygons at its place in the output (the parts' order), written in parallel.
  std::vector<std::size_t> start(parts.size() + 1, 0);
  for (std::size_t part = 0; part < parts.size(); ++part) {
    std::size_t count = 0;
    for (const auto& s3 : parts[part])
      for (const PolygonSlot& s : s3) count += s.size > 0;
    start[part + 1] = start[part] + count;
  }
  out.vertices.resize(start.back());
  out.size.resize(start.back());
  out.edge.resize(start.back());
  out.edge_point.resize(start.back());
  const int first_extra = vertex_count();
  tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t part) {
    std::size_t at = start[part];
    for (const auto& s3 : parts[part])
      for (const PolygonSlot& s : s3) {
        if (s.size == 0) continue;
        std::array<int, 8> ids = s.vertices;
        std::size_t next = 0;
        for (int i = 0; i < s.size; ++i) {
          if (ids[std::size_t(i)] >= 0) continue;
          const auto it =
              std::lower_bound(segments.begin(), segments.end(), s.segments[next++].key,
                               [](const auto& x, std::int64_t k) { return x.first < k; });
          ids[std::size_t(i)] = first_extra + int(it - segments.begin());
        }
        out.vertices[at] = ids;
        out.size[at] = std::int8_t(s.size);
        out.edge[at] = s.edge;
        out.edge_point[at] = s.edge_point;
        ++at;
      }
    parts[part] = {};  // (freed by the thread that made it)
  });
  return out;
}

}  // namespace sdfcontour::detail
