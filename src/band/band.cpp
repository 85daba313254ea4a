#include "sdfcontour/band/band.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "input/value_scans.h"
#include "input/windowed_passes.h"
#include "sdfcontour/band/point_clusters.h"

namespace sdfcontour {

namespace {

// Fewer samples at a sign's extreme than this are a coincidence (a grid's corners, a centre).
constexpr long kMinTruncatedSamples = 64;

// Keep sample i when it lies in the band or its margin and carries a distance; it is a core
// sample (one that gives a contact point) when it lies in the band and a margin away from a
// truncation distance.
struct BandTest {
  double keep_limit;  // (band + margin) * h
  double core_limit;  // band * h
  double margin;      // margin * h
  Truncation truncation;
  bool operator()(double v) const { return std::abs(v) <= keep_limit && !truncation.truncated(v); }
  // The largest |value| of a core sample on one side.
  double core_bound(bool inside) const {
    const double t = inside ? truncation.inside : truncation.outside;
    return std::min(core_limit, t * (1 - kTruncationTolerance) - margin);
  }
  bool core(double v) const { return std::abs(v) <= core_bound(v < 0); }
};

BandTest make_test(const BandOptions& options, double h, const Truncation& truncation) {
  return {(options.band + options.margin) * h, options.band * h, options.margin * h, truncation};
}

// 4 as "4", 2.5 as "2.5" (std::to_string writes 4.000000).
std::string shortest(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

void require_usable(const BandSamples& b, const BandOptions& options) {
  const Eigen::Index n = b.samples.values.size();
  bool inside = false, outside = false;
  for (Eigen::Index i = 0; i < n; ++i)
    if (b.core[std::size_t(i)]) (b.samples.values[i] < 0 ? inside : outside) = true;
  if (n < 4 || !(inside && outside))
    throw Error("only " + std::to_string(n) + " samples lie within the band of " +
                shortest(options.band) + " spacings" +
                (b.truncation.detected() ? " and inside the truncation distance" : "") +
                (n >= 4 ? ", and they have no sign change" : "") +
                "; widen it with --band (or --band all)");
}

// `drop_pages`: the grid's page dropper (GridView::drop_pages), or null.
template <class T>
TruncationCounts counts_in(const T* values, std::size_t n,
                           const std::function<void(const void*, std::size_t)>* drop_pages) {
  auto never = [](const auto&) { return false; };
  TruncationCounts c = detail::windowed_reduce(
      drop_pages, values, n, TruncationCounts{},
      [&](const tbb::blocked_range<std::size_t>& r, TruncationCounts x) {
        detail::extremes(values + r.begin(), r.size(), x.most_negative, x.most_positive);
        return x;
      },
      [](TruncationCounts a, TruncationCounts b) {
        a.most_negative = std::min(a.most_negative, b.most_negative);
        a.most_positive = std::max(a.most_positive, b.most_positive);
        return a;
      },
      never);
  const double lo = -c.most_negative * (1 - kTruncationTolerance),
               hi = c.most_positive * (1 - kTruncationTolerance);
  const TruncationCounts at = detail::windowed_reduce(
      drop_pages, values, n, TruncationCounts{},
      [&](const tbb::blocked_range<std::size_t>& r, TruncationCounts x) {
        detail::count_beyond(values + r.begin(), r.size(), lo, hi, x.negatives, x.at_inside,
                             x.at_outside);
        return x;
      },
      [](TruncationCounts a, TruncationCounts b) {
        a.at_inside += b.at_inside, a.at_outside += b.at_outside, a.negatives += b.negatives;
        return a;
      },
      never);
  c.at_inside = at.at_inside, c.at_outside = at.at_outside, c.negatives = at.negatives;
  c.count = long(n);
  return c;
}

}  // namespace

TruncationCounts truncation_counts(const GridView& part) {
  return part.visit([&](const auto* f) { return counts_in(f, part.size(), part.drop_pages); });
}

Truncation truncation_of_parts(const std::vector<TruncationCounts>& parts, double min_fraction) {
  TruncationCounts whole;
  for (const TruncationCounts& p : parts) {
    whole.most_negative = std::min(whole.most_negative, p.most_negative);
    whole.most_positive = std::max(whole.most_positive, p.most_positive);
    whole.negatives += p.negatives, whole.count += p.count;
  }
  for (const TruncationCounts& p : parts) {
    if (-p.most_negative >= -whole.most_negative * (1 - kTruncationTolerance))
      whole.at_inside += p.at_inside;
    if (p.most_positive >= whole.most_positive * (1 - kTruncationTolerance))
      whole.at_outside += p.at_outside;
  }
  auto clamped = [&](long at_extreme, long of_sign) {
    return at_extreme >= kMinTruncatedSamples &&
           double(at_extreme) >= min_fraction * double(of_sign);
  };
  Truncation t;
  if (whole.most_negative < 0 && clamped(whole.at_inside, whole.negatives))
    t.inside = -whole.most_negative;
  if (whole.most_positive > 0 && clamped(whole.at_outside, whole.count - whole.negatives))
    t.outside = whole.most_positive;
  return t;
}

Truncation detect_truncation(const Eigen::VectorXd& values, double min_fraction) {
  return truncation_of_parts({counts_in(values.data(), std::size_t(values.size()), nullptr)},
                             min_fraction);
}

Truncation detect_truncation(const GridView& grid, double min_fraction) {
  return truncation_of_parts({truncation_counts(grid)}, min_fraction);
}

namespace {

template <class Values>
Truncation resolve(const Values& values, const BandOptions& options) {
  switch (options.truncation_mode) {
    case TruncationMode::Auto:
      return detect_truncation(values);
    case TruncationMode::Given: {
      Truncation t;
      t.inside = t.outside = options.truncation;
      return t;
    }
    case TruncationMode::Resolved:
      return options.resolved;
    case TruncationMode::None:
      break;
  }
  return {};
}

// What both selections start with: checked options, the spacing, the truncation, the test.
template <class Values>
BandTest begin_band(BandSamples& out, const Values& values, const BandOptions& options, double h) {
  validate_band_options(options);
  out.spacing = h;
  out.band = options.band;
  out.truncation = resolve(values, options);
  const BandTest test = make_test(options, h / options.value_scale, out.truncation);
  out.core_inside = test.core_bound(true) * options.value_scale;
  out.core_outside = test.core_bound(false) * options.value_scale;
  return test;
}

// The selected values and the truncation in distance units.
void scale_values(BandSamples& out, const BandOptions& options) {
  if (options.value_scale == 1.0) return;
  out.samples.values *= options.value_scale;
  out.truncation.inside *= options.value_scale;
  out.truncation.outside *= options.value_scale;
}

}  // namespace

Truncation resolve_truncation(const Eigen::VectorXd& values, const BandOptions& options) {
  return resolve(values, options);
}

Truncation resolve_truncation(const GridView& grid, const BandOptions& options) {
  return resolve(grid, options);
}

double auto_band(double samples_per_axis) {
  return samples_per_axis < 128 ? 8.0 : samples_per_axis < 256 ? 4.0 : 3.0;
}

double auto_local_band(double samples_per_axis, bool lattice_points) {
  if (samples_per_axis >= 384) return auto_band(samples_per_axis);
  return lattice_points && samples_per_axis >= 128 ? 6.0 : 8.0;
}

void validate_band_options(const BandOptions& options) {
  if (!(options.band >= 0))
    throw Error("the band must be a positive number of spacings (or 'all' or 'auto'), got " +
                std::to_string(options.band));
  if (!(options.margin >= 0) || !std::isfinite(options.margin))
    throw Error("the band's margin must be a non-negative number of spacings");
  if (options.truncation_mode == TruncationMode::Given &&
      !(options.truncation > 0 && std::isfinite(options.truncation)))
    throw Error("the truncation distance must be positive and finite");
  if (!(options.value_scale > 0) || !std::isfinite(options.value_scale))
    throw Error("the value scale must be positive and finite");
}

BandSamples select_band(const GridView& grid, const BandOptions& given) {
  BandOptions options = given;
  BandSamples out;
  const std::array<int, 3> whole = grid.whole_dims();  // a block's band is its whole grid's
  out.samples_per_axis = double(*std::max_element(whole.begin(), whole.end()));
  if (options.band == 0) options.band = auto_band(out.samples_per_axis);
  const BandTest keep = begin_band(out, grid, options, grid.spacing().maxCoeff());
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  // Per-slab counts, then each slab fills its own rows: C order for any thread count.
  std::vector<Eigen::Index> slab_start(std::size_t(nx) + 1, 0);
  grid.visit([&](const auto* f) {
    tbb::parallel_for(0, nx, [&](int i) {
      Eigen::Index c = 0;
      const std::size_t begin = grid.index(i, 0, 0), end = begin + std::size_t(ny) * nz;
      for (std::size_t p = begin; p < end; ++p) c += keep(double(f[p]));
      slab_start[std::size_t(i) + 1] = c;
    });
  });
  for (int i = 0; i < nx; ++i) slab_start[std::size_t(i) + 1] += slab_start[std::size_t(i)];
  const Eigen::Index count = slab_start.back();
  out.samples.points.resize(count, 3);
  out.samples.values.resize(count);
  out.source.resize(std::size_t(count));
  out.core.resize(std::size_t(count));
  grid.visit([&](const auto* f) {
    tbb::parallel_for(0, nx, [&](int i) {
      Eigen::Index at = slab_start[std::size_t(i)];
      for (int j = 0; j < ny; ++j)
        for (int k = 0; k < nz; ++k) {
          const std::size_t p = grid.index(i, j, k);
          const double v = f[p];
          if (!keep(v)) continue;
          out.samples.points.row(at) = grid.point(i, j, k).transpose();
          out.samples.values[at] = v;
          out.core[std::size_t(at)] = keep.core(v);
          out.source[std::size_t(at++)] = long(p);
        }
    });
  });
  scale_values(out, options);
  require_usable(out, options);
  return out;
}

BandSamples select_band(const Grid& grid, const BandOptions& options) {
  return select_band(view_of(grid), options);
}

BandSamples select_band(const SparseGrid& grid, const BandOptions& given) {
  BandOptions options = given;
  BandSamples out;
  out.samples_per_axis = double(*std::max_element(grid.dims.begin(), grid.dims.end()));
  if (options.band == 0) options.band = auto_band(out.samples_per_axis);
  // A sparse grid holds a sampled field: nothing to detect a truncation in.
  const BandTest keep = begin_band(out, Eigen::VectorXd(), options, grid.spacing().maxCoeff());
  // Each block's own samples in the band (by global index), then all in the grid's C order.
  std::vector<std::vector<std::pair<long, double>>> found(grid.blocks.size());
  tbb::parallel_for(std::size_t(0), grid.blocks.size(), [&](std::size_t s) {
    const GridView& block = grid.blocks[s];
    const std::array<int, 3> own = owned_dims(grid, block);
    for (int i = 0; i < own[0]; ++i)
      for (int j = 0; j < own[1]; ++j)
        for (int k = 0; k < own[2]; ++k) {
          const double v = block.value(block.index(i, j, k));
          if (keep(v))
            found[s].emplace_back(
                long(grid.index(block.first[0] + i, block.first[1] + j, block.first[2] + k)), v);
        }
  });
  std::vector<std::pair<long, double>> kept;
  for (const auto& f : found) kept.insert(kept.end(), f.begin(), f.end());
  tbb::parallel_sort(kept.begin(), kept.end());
  const Eigen::Index count = Eigen::Index(kept.size());
  out.samples.points.resize(count, 3);
  out.samples.values.resize(count);
  out.source.resize(std::size_t(count));
  out.core.resize(std::size_t(count));
  const long nz = grid.dims[2], nyz = long(grid.dims[1]) * nz;
  tbb::parallel_for(Eigen::Index(0), count, [&](Eigen::Index r) {
    const auto [p, v] = kept[std::size_t(r)];
    out.samples.points.row(r) =
        grid.point(int(p / nyz), int(p % nyz / nz), int(p % nz)).transpose();
    out.samples.values[r] = v;
    out.core[std::size_t(r)] = keep.core(v);
    out.source[std::size_t(r)] = p;
  });
  scale_values(out, options);
  require_usable(out, options);
  return out;
}

namespace {

// The side of a cube holding one sample on average, measured in the box of the central 98% of
// the samples on each axis, so that a stray sample far away does not inflate it.
double robust_spacing(const PointMatrix& points) {
  const Eigen::Index n = points.rows();
  Eigen::Vector3d extent;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> x(points.col(a).data(), points.col(a).data() + n);
    const auto lo = x.begin() + long(0.01 * double(n - 1)),
               hi = x.begin() + long(0.99 * double(n - 1));
    std::nth_element(x.begin(), lo, x.end());
    const double low = *lo;
    std::nth_element(x.begin(), hi, x.end());
    extent[a] = *hi - low;
  }
  // The central 98% of each axis holds 0.98^3 of uniformly spread samples.
  const double volume = extent.prod(), inner = 0.98 * 0.98 * 0.98 * double(n);
  // A flat box still has a spacing: measure it in the largest extent then.
  return volume > 0 ? std::cbrt(volume / inner) : extent.maxCoeff() / std::cbrt(inner);
}

}  // namespace

BandSamples select_band(const Samples& samples, const BandOptions& given, double spacing) {
  const Eigen::Index n = samples.points.rows();
  const double h0 = spacing > 0 ? spacing : robust_spacing(samples.points);
  // A sample with fewer than 3 others within a few spacings (a stray row far from the rest)
  // makes no tetrahedron of its own size: its gradient, and so its contact point, would come
  // from tetrahedra spanning the gap. Such samples are dropped, and counted.
  std::vector<char> usable(static_cast<std::size_t>(n), 1);
  BandSamples out;
  if (h0 > 0) {
    const std::vector<int> cluster = point_clusters(samples.points, kIsolationReach * h0);
    std::vector<int> members(std::size_t(*std::max_element(cluster.begin(), cluster.end()) + 1));
    for (int c : cluster) ++members[std::size_t(c)];
    for (Eigen::Index i = 0; i < n; ++i)
      if (members[std::size_t(cluster[std::size_t(i)])] < 4) usable[std::size_t(i)] = 0;
    out.isolated = long(std::count(usable.begin(), usable.end(), 0));
    if (out.isolated == long(n))
      throw Error("every sample lies alone, more than " + shortest(kIsolationReach) +
                  " spacings from 3 others: no surface can be found");
  }
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = -low;
  for (Eigen::Index i = 0; i < n; ++i)
    if (usable[std::size_t(i)]) {
      low = low.cwiseMin(samples.points.row(i).transpose());
      high = high.cwiseMax(samples.points.row(i).transpose());
    }
  const Eigen::Vector3d extent = high - low;
  const double h = h0;
  BandOptions options = given;
  out.samples_per_axis = extent.maxCoeff() / h + 1;
  if (options.band == 0) options.band = auto_band(out.samples_per_axis);
  const BandTest keep = begin_band(out, samples.values, options, h);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < n; ++i)
    if (usable[std::size_t(i)] && keep(samples.values[i])) kept.push_back(i);
  out.samples = samples_at(samples, kept);
  out.source.resize(kept.size());
  out.core.resize(kept.size());
  for (std::size_t r = 0; r < kept.size(); ++r) {
    out.core[r] = keep.core(samples.values[kept[r]]);
    out.source[r] = long(kept[r]);
  }
  scale_values(out, options);
  require_usable(out, options);
  return out;
}

long sign_change_edges(const GridView& grid) {
  const int nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const std::size_t stride[3] = {std::size_t(ny) * std::size_t(nz), std::size_t(nz), 1};
  std::vector<long> per_slab(static_cast<std::size_t>(nx), 0);
  grid.visit([&](const auto* f) {
    tbb::parallel_for(0, nx, [&](int i) {
      long count = 0;
      for (int j = 0; j < ny; ++j)
        for (int k = 0; k < nz; ++k) {
          const std::size_t p = grid.index(i, j, k);
          const bool inside = f[p] < 0;
          if (i + 1 < nx) count += (f[p + stride[0]] < 0) != inside;
          if (j + 1 < ny) count += (f[p + stride[1]] < 0) != inside;
          if (k + 1 < nz) count += (f[p + stride[2]] < 0) != inside;
        }
      per_slab[std::size_t(i)] = count;
    });
  });
  long total = 0;
  for (long c : per_slab) total += c;
  return total;
}

Samples core_samples(const BandSamples& band) {
  std::vector<Eigen::Index> core;
  for (Eigen::Index i = 0; i < band.samples.values.size(); ++i)
    if (band.core[std::size_t(i)]) core.push_back(i);
  return samples_at(band.samples, core);
}

}  // namespace sdfcontour
