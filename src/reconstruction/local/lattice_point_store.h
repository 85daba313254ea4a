// Internal: the lattice's contact points that a grid's bricks made, so that each sample's point is
// made once and not again by every later brick whose reach covers it (local_mesh_in_bricks).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/input/samples.h"

namespace sdfcontour::detail {

/// A sample's lattice contact point reads the whole grid's values alone (a brick checks its block
/// holds all it reads: require_lattice_reach), so any brick's point of it is every brick's.
/// Each brick that made points for the core samples in a global box records the box and its
/// points; the first recorded box that holds a sample decided it (its point, or none).
/// Bricks must be recorded in ascending order of their boxes' first corner along the first axis
/// (the bricks' C order), one at a time.
class LatticePointStore {
 public:
  /// Of `band` (a block's, `source` in the block's C order), the `flagged` samples, all in the
  /// global box [lo, hi] (inclusive), that a recorded box holds are cleared there; returns their
  /// points (with `samples` indexing `band`, ascending). Drops the records whose box ends before
  /// `lo` along the first axis: no later brick reads there.
  ContactPoints take(const GridGeometry& block, const BandSamples& band,
                     const std::array<int, 3>& lo, const std::array<int, 3>& hi,
                     std::vector<char>& flagged);
  /// Records the points `made` (of `band`'s samples) as those of the core samples in the global box
  /// [lo, hi] (inclusive) that no recorded box held: `made` must be all those samples' points.
  /// Those with every coordinate at most `unshared`'s, which no later brick reads (its reach
  /// begins past them along some axis), are not kept: a take that needs one throws InternalError.
  void record(const GridGeometry& block, const BandSamples& band, const std::array<int, 3>& lo,
              const std::array<int, 3>& hi, const std::array<int, 3>& unshared,
              const ContactPoints& made);

 private:
  struct Record {
    std::array<int, 3> lo, hi;           ///< the global box, inclusive
    std::array<int, 3> unshared;         ///< samples in [lo, unshared] are not kept
    std::vector<std::uint64_t> samples;  ///< its points' global C-order indices, ascending
    PointMatrix points, normals;
  };
  std::vector<Record> records_;
};

/// Two sets of one band's contact points with distinct samples, as one in band order.
ContactPoints merged_contact_points(const ContactPoints& a, const ContactPoints& b);

}  // namespace sdfcontour::detail
