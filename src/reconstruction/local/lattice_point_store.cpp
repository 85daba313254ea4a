// The lattice's contact points that a grid's bricks made (lattice_point_store.h).
#include "reconstruction/local/lattice_point_store.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

#include "reconstruction/local/brick_ownership.h"

namespace sdfcontour::detail {

namespace {

using Index3 = std::array<int, 3>;

bool inside(const Index3& at, const Index3& lo, const Index3& hi) {
  for (std::size_t a = 0; a < 3; ++a)
    if (at[a] < lo[a] || at[a] > hi[a]) return false;
  return true;
}

bool meet(const Index3& lo1, const Index3& hi1, const Index3& lo2, const Index3& hi2) {
  for (std::size_t a = 0; a < 3; ++a)
    if (hi1[a] < lo2[a] || hi2[a] < lo1[a]) return false;
  return true;
}

}  // namespace

ContactPoints LatticePointStore::take(const GridGeometry& block, const BandSamples& band,
                                      const Index3& lo, const Index3& hi,
                                      std::vector<char>& flagged) {
  records_.erase(std::remove_if(records_.begin(), records_.end(),
                                [&](const Record& r) { return r.hi[0] < lo[0]; }),
                 records_.end());
  std::vector<const Record*> near;  // in the order recorded
  for (const Record& r : records_)
    if (meet(r.lo, r.hi, lo, hi)) near.push_back(&r);
  // Per band sample, the record and row of its stored point (row -1: decided, no point).
  std::vector<std::pair<int, long>> from(flagged.size(), {-1, -1});
  const Index3 n = block.whole_dims();
  tbb::parallel_for(std::size_t(0), flagged.size(), [&](std::size_t s) {
    if (!flagged[s]) return;
    const Index3 at = global_sample(block, band, s);
    for (std::size_t r = 0; r < near.size(); ++r) {
      if (!inside(at, near[r]->lo, near[r]->hi)) continue;
      if (inside(at, near[r]->lo, near[r]->unshared))
        throw InternalError("a brick read a lattice point that an earlier one did not keep");
      const std::vector<std::uint64_t>& made = near[r]->samples;
      const std::uint64_t index = grid_index_of(at, n);
      const auto it = std::lower_bound(made.begin(), made.end(), index);
      const bool has = it != made.end() && *it == index;
      from[s] = {int(r), has ? long(it - made.begin()) : -1};
      flagged[s] = 0;
      return;
    }
  });
  ContactPoints cp;
  for (std::size_t s = 0; s < from.size(); ++s)
    if (from[s].second >= 0) cp.samples.push_back(int(s));
  cp.points.resize(Eigen::Index(cp.samples.size()), 3);
  cp.normals.resize(Eigen::Index(cp.samples.size()), 3);
  for (std::size_t q = 0; q < cp.samples.size(); ++q) {
    const auto [r, row] = from[std::size_t(cp.samples[q])];
    cp.points.row(Eigen::Index(q)) = near[std::size_t(r)]->points.row(row);
    cp.normals.row(Eigen::Index(q)) = near[std::size_t(r)]->normals.row(row);
  }
  return cp;
}

void LatticePointStore::record(const GridGeometry& block, const BandSamples& band, const Index3& lo,
                               const Index3& hi, const Index3& unshared,
                               const ContactPoints& made) {
  Record r{lo, hi, unshared, {}, {}, {}};
  const Index3 n = block.whole_dims();
  std::vector<Eigen::Index> rows;
  // (A block's C order is the whole grid's inside it: the indices stay ascending.)
  for (std::size_t q = 0; q < made.samples.size(); ++q) {
    const Index3 at = global_sample(block, band, std::size_t(made.samples[q]));
    if (inside(at, lo, unshared)) continue;
    rows.push_back(Eigen::Index(q));
    r.samples.push_back(grid_index_of(at, n));
  }
  r.points = made.points(rows, Eigen::all);
  r.normals = made.normals(rows, Eigen::all);
  records_.push_back(std::move(r));
}

ContactPoints merged_contact_points(const ContactPoints& a, const ContactPoints& b) {
  ContactPoints out;
  const Eigen::Index rows = Eigen::Index(a.samples.size() + b.samples.size());
  out.points.resize(rows, 3);
  out.normals.resize(rows, 3);
  out.samples.reserve(std::size_t(rows));
  std::size_t i = 0, j = 0;
  for (Eigen::Index q = 0; q < rows; ++q) {
    const bool from_a =
        j == b.samples.size() || (i < a.samples.size() && a.samples[i] < b.samples[j]);
    const ContactPoints& src = from_a ? a : b;
    std::size_t& at = from_a ? i : j;
    out.samples.push_back(src.samples[at]);
    out.points.row(q) = src.points.row(Eigen::Index(at));
    out.normals.row(q) = src.normals.row(Eigen::Index(at));
    ++at;
  }
  out.hidden = a.hidden + b.hidden;
  out.zero_gradient = a.zero_gradient + b.zero_gradient;
  out.discarded = a.discarded + b.discarded;
  out.rescued = a.rescued + b.rescued;
  return out;
}

}  // namespace sdfcontour::detail
