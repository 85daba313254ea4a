// The band samples' lattice for the sphere search (lattice_spheres.h).
#include "contact_points/lattice_spheres.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <limits>

#include "input/cpu_clones.h"
#include "pipeline/float_bounds.h"

namespace sdfcontour::detail {

Lattice::Lattice(const GridGeometry& grid, const BandSamples& band)
    : band_(band),
      n_(grid.dims),
      origin_(grid.point(0, 0, 0)),
      h_(grid.spacing()),
      radius_up_(new float[band.source.size()]),
      column_runs_(std::size_t(n_[0]) * n_[1] + 1, 0),
      column_max_(std::size_t(n_[0]) * n_[1], 0.0f) {
  const std::size_t samples = band.source.size(), columns = column_max_.size();
  if (samples > std::size_t(std::numeric_limits<int>::max()))
    throw Error("too many band samples in one brick: use smaller bricks (--brick-size)");
  const bool sorted = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(1, std::max<std::size_t>(samples, 1)), true,
      [&](auto r, bool ok) {
        for (std::size_t s = r.begin(); ok && s < r.end(); ++s)
          ok = band.source[s - 1] < band.source[s];
        return ok;
      },
      [](bool a, bool b) { return a && b; });
  if (!sorted) throw InternalError("the lattice's band samples are not in the grid's order");
  tbb::parallel_for(std::size_t(0), samples, [&](std::size_t s) {
    radius_up_[s] = float_above(std::abs(band.samples.values[Eigen::Index(s)]));
  });
  // Each column's band samples, then its runs: counted, numbered in column order, filled.
  const long nz = n_[2];
  auto k_of = [&](int s) { return int(band.source[std::size_t(s)] % nz); };
  std::vector<int> column_begin(columns + 1);
  tbb::parallel_for(std::size_t(0), columns + 1, [&](std::size_t column) {
    column_begin[column] =
        int(std::lower_bound(band.source.begin(), band.source.end(), long(column) * nz) -
            band.source.begin());
  });
  tbb::parallel_for(std::size_t(0), columns, [&](std::size_t column) {
    int runs = 0;
    for (int s = column_begin[column]; s < column_begin[column + 1]; ++s)
      runs += s == column_begin[column] || k_of(s) != k_of(s - 1) + 1;
    column_runs_[column + 1] = runs;
  });
  for (std::size_t column = 0; column < columns; ++column)
    column_runs_[column + 1] += column_runs_[column];
  runs_.resize(std::size_t(column_runs_.back()) + 1);
  tbb::parallel_for(std::size_t(0), columns, [&](std::size_t column) {
    int r = column_runs_[column];
    for (int s = column_begin[column]; s < column_begin[column + 1]; ++s)
      if (s == column_begin[column] || k_of(s) != k_of(s - 1) + 1)
        runs_[std::size_t(r++)] = {s, k_of(s), 0};
  });
  runs_.back() = {int(samples), 0, 0};
  // Chunk maxima: each run's chunks counted, numbered in run order, filled.
  int chunks = 0;
  for (std::size_t r = 0; r + 1 < runs_.size(); ++r) {
    const int last = runs_[r].first + runs_[r + 1].begin - 1 - runs_[r].begin;
    runs_[r].chunks = chunks;
    chunks += last / kChunk - runs_[r].first / kChunk + 1;
  }
  runs_.back().chunks = chunks;
  chunk_max_.assign(std::size_t(chunks), 0.0f);
  tbb::parallel_for(std::size_t(0), columns, [&](std::size_t column) {
    for (int r = column_runs_[column]; r < column_runs_[column + 1]; ++r) {
      const Run& run = runs_[std::size_t(r)];
      for (int s = run.begin; s < runs_[std::size_t(r) + 1].begin; ++s) {
        const float up = radius_up_[std::size_t(s)];
        float& chunk = chunk_max_[std::size_t(run.chunks + (run.first + s - run.begin) / kChunk -
                                              run.first / kChunk)];
        chunk = std::max(chunk, up);
        column_max_[column] = std::max(column_max_[column], up);
      }
    }
  });
  largest_ = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, columns), 0.0,
      [&](auto r, double m) {
        for (std::size_t c = r.begin(); c < r.end(); ++c) m = std::max(m, double(column_max_[c]));
        return m;
      },
      [](double a, double b) { return std::max(a, b); });
}

// Blocks of spheres counted branch-free, then the first that may reach within the block. The
// slack keeps every sphere that the exact test (any_sphere_near's, in whatever rounding) takes.
// (An AVX2 clone: cpu_clones.h.)
SDFCONTOUR_AVX2_CLONE std::size_t SphereList::next_near(const Eigen::Vector3d& c, double extra,
                                                        std::size_t t) const {
  const double* __restrict px = x.data();
  const double* __restrict py = y.data();
  const double* __restrict pz = z.data();
  const double* __restrict pr = r.data();
  const double cx = c[0], cy = c[1], cz = c[2];
  auto may_reach = [&](std::size_t u) {
    const double dx = px[u] - cx, dy = py[u] - cy, dz = pz[u] - cz, reach = pr[u] + extra;
    return (dx * dx + dy * dy) + dz * dz < reach * reach * (1 + 1e-9);
  };
  constexpr std::size_t kBlock = 16;
  const std::size_t n = r.size();
  for (; t + kBlock <= n; t += kBlock) {
    int count = 0;
    for (std::size_t u = t; u < t + kBlock; ++u) count += may_reach(u);
    if (count > 0) break;
  }
  for (; t < n; ++t)
    if (may_reach(t)) return t;
  return n;
}

void Lattice::gather(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double widen,
                     SphereList& out) const {
  out.lo = lo, out.hi = hi, out.widen = widen;
  for (auto* v : {&out.x, &out.y, &out.z, &out.r}) v->clear();
  out.sample.clear();
  // The box widened by a hair more, so that rounding cannot leave out a sphere that a point's own
  // test would find.
  const Eigen::Vector3d slop = 1e-9 * h_;
  const Eigen::Vector3d a = lo - slop, b = hi + slop;
  auto take = [&](const Run& run, int i, int j, int ka, int kb, double across) {
    const double x = origin_[0] + i * h_[0], y = origin_[1] + j * h_[1];
    return for_each_chunk_near(run, ka, kb, a[2], b[2], across, widen, [&](int first, int last) {
      for (int k = first; k <= last; ++k) {
        const long t = run.begin + k - run.first;
        const double z = origin_[2] + k * h_[2];
        const double dz = z < a[2] ? a[2] - z : (z > b[2] ? z - b[2] : 0.0);
        const double bound = double(radius_up_[std::size_t(t)]) + widen;
        if (!(across + dz * dz < bound * bound)) continue;
        out.x.push_back(x), out.y.push_back(y), out.z.push_back(z);
        out.r.push_back(std::abs(value(t)));
        out.sample.push_back(t);
      }
      return false;
    });
  };
  for_each_column_near(a, b, widen, take);
}

}  // namespace sdfcontour::detail
