// Internal: the adaptive octree's topology, per depth: active cells, their corner nodes, and each
// node's neighbours. Complete down to the full depth; below, a cell is refined where points want
// that depth (within a dilation), so finer depths cover only a band around the points.
#pragma once

#include <array>
#include <vector>

#include "reconstruction/poisson/keys.h"
#include "reconstruction/poisson/points.h"

namespace sdfcontour::poisson {

/// One depth of the octree.
struct OctreeLevel {
  int depth = 0;
  long res = 0;            ///< cells per axis
  double h = 0;            ///< cell side (unit cube)
  std::vector<Key> cells;  ///< sorted active cells
  LineIndex cell_lines;
  std::vector<char> refined;  ///< per active cell: its children are active
  std::vector<Key> nodes;     ///< sorted corners of active cells
  LineIndex node_lines;

  /// Index of node (i, j, k), or -1.
  int node(long i, long j, long k) const {
    if (i < 0 || j < 0 || k < 0 || i > res || j > res || k > res) return -1;
    return node_lines.find(nodes, pack(i, j, k));
  }
  /// Indices of the corner nodes of cell c (corner bits x=1, y=2, z=4).
  std::array<int, 8> corner_nodes(const std::array<long, 3>& c) const {
    std::array<int, 8> n;
    for (int a = 0; a < 8; ++a)
      n[std::size_t(a)] = node(c[0] + (a & 1), c[1] + (a >> 1 & 1), c[2] + (a >> 2 & 1));
    return n;
  }
  /// Index of the active cell with this key, or -1.
  int cell(Key key) const { return cell_lines.find(cells, key); }
  bool on_face(long i, long j, long k) const {
    return i == 0 || j == 0 || k == 0 || i == res || j == res || k == res;
  }
};

struct Octree {
  int min_depth = 0;                ///< complete down to here
  int finest = 0;                   ///< the finest depth with active cells
  std::vector<OctreeLevel> levels;  ///< indexed by depth; empty below min_depth
  OctreeLevel& level(int d) { return levels[std::size_t(d)]; }
  const OctreeLevel& level(int d) const { return levels[std::size_t(d)]; }
};

/// The octree down to max_depth: complete to min_depth; a depth-(d-1) cell is refined when it
/// holds a point splatted at depth d-1 or finer, dilated by `dilation` cells
/// (PoissonOptions::refine_dilation). `cancel` (optional) is checked at each depth (throws
/// Cancelled).
Octree build_octree(const std::vector<UnitPoint>& points, const MortonRuns& runs, int min_depth,
                    int max_depth, int dilation = 2, const std::atomic<bool>* cancel = nullptr);

/// Per node of L: whether it is solved for (every incident cell inside the domain is active, so
/// its row of the system is complete; Dirichlet boundaries also fix the domain's faces).
std::vector<char> solved_nodes(const OctreeLevel& L, PoissonBoundary boundary);

/// Values on the finer level's nodes from the coarser level's (exact: trilinear functions nest).
std::vector<double> prolong_values(const OctreeLevel& coarse, const OctreeLevel& fine,
                                   const std::vector<double>& values);

}  // namespace sdfcontour::poisson
