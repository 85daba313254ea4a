#include "sdfcontour/band.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <string>

namespace sdfcontour {

namespace {

// Values within this relative distance of a truncation value count as truncated: writers
// store T in float32 and may round it.
constexpr double kTruncationTolerance = 1e-6;
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
  bool core(double v) const {
    const double t = v < 0 ? truncation.inside : truncation.outside;
    return std::abs(v) <= core_limit && std::abs(v) <= t * (1 - kTruncationTolerance) - margin;
  }
};

BandTest make_test(const BandOptions& options, double h, const Truncation& truncation) {
  return {(options.band + options.margin) * h, options.band * h, options.margin * h, truncation};
}

void require_usable(const BandSamples& b, const BandOptions& options) {
  const Eigen::Index n = b.samples.values.size();
  bool inside = false, outside = false;
  for (Eigen::Index i = 0; i < n; ++i)
    if (b.core[std::size_t(i)]) (b.samples.values[i] < 0 ? inside : outside) = true;
  if (n < 4 || !(inside && outside))
    throw Error("only " + std::to_string(n) + " samples lie within the band of " +
                std::to_string(options.band) + " spacings" +
                (b.truncation.detected() ? " and inside the truncation distance" : "") +
                (n >= 4 ? ", and they have no sign change" : "") +
                "; widen it with --band (or --band all)");
}

}  // namespace

bool Truncation::truncated(double value) const {
  const double t = value < 0 ? inside : outside;
  return std::abs(value) >= t * (1 - kTruncationTolerance);
}

namespace {

template <class T>
Truncation detect_in(const T* values, std::size_t n, double min_fraction) {
  struct Extremes {
    double most_negative = 0, most_positive = 0;
  };
  const Extremes e = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 1 << 16), Extremes{},
      [&](const tbb::blocked_range<std::size_t>& r, Extremes x) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          x.most_negative = std::min(x.most_negative, double(values[i]));
          x.most_positive = std::max(x.most_positive, double(values[i]));
        }
        return x;
      },
      [](Extremes a, Extremes b) {
        return Extremes{std::min(a.most_negative, b.most_negative),
                        std::max(a.most_positive, b.most_positive)};
      });
  const double lo = -e.most_negative * (1 - kTruncationTolerance),
               hi = e.most_positive * (1 - kTruncationTolerance);
  struct Counts {
    long at_inside = 0, at_outside = 0, negatives = 0;
  };
  const Counts c = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 1 << 16), Counts{},
      [&](const tbb::blocked_range<std::size_t>& r, Counts x) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          const double v = values[i];
          x.negatives += v < 0;
          x.at_inside += v < 0 && -v >= lo;
          x.at_outside += v > 0 && v >= hi;
        }
        return x;
      },
      [](Counts a, Counts b) {
        return Counts{a.at_inside + b.at_inside, a.at_outside + b.at_outside,
                      a.negatives + b.negatives};
      });
  auto clamped = [&](long at_extreme, long of_sign) {
    return at_extreme >= kMinTruncatedSamples &&
           double(at_extreme) >= min_fraction * double(of_sign);
  };
  Truncation t;
  if (e.most_negative < 0 && clamped(c.at_inside, c.negatives)) t.inside = -e.most_negative;
  if (e.most_positive > 0 && clamped(c.at_outside, long(n) - c.negatives))
    t.outside = e.most_positive;
  return t;
}

}  // namespace

Truncation detect_truncation(const Eigen::VectorXd& values, double min_fraction) {
  return detect_in(values.data(), std::size_t(values.size()), min_fraction);
}

Truncation detect_truncation(const GridView& grid, double min_fraction) {
  return grid.visit([&](const auto* f) { return detect_in(f, grid.size(), min_fraction); });
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
  out.truncation = resolve(values, options);
  return make_test(options, h, out.truncation);
}

}  // namespace

Truncation resolve_truncation(const Eigen::VectorXd& values, const BandOptions& options) {
  return resolve(values, options);
}

Truncation resolve_truncation(const GridView& grid, const BandOptions& options) {
  return resolve(grid, options);
}

void validate_band_options(const BandOptions& options) {
  if (!(options.band > 0))
    throw Error("the band must be a positive number of spacings (or 'all'), got " +
                std::to_string(options.band));
  if (!(options.margin >= 0) || !std::isfinite(options.margin))
    throw Error("the band's margin must be a non-negative number of spacings");
  if (options.truncation_mode == TruncationMode::Given &&
      !(options.truncation > 0 && std::isfinite(options.truncation)))
    throw Error("the truncation distance must be positive and finite");
}

BandSamples select_band(const GridView& grid, const BandOptions& options) {
  BandSamples out;
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
  require_usable(out, options);
  return out;
}

BandSamples select_band(const Grid& grid, const BandOptions& options) {
  return select_band(view_of(grid), options);
}

BandSamples select_band(const Samples& samples, const BandOptions& options, double spacing) {
  const Eigen::Index n = samples.points.rows();
  const Eigen::Vector3d extent =
      samples.points.colwise().maxCoeff() - samples.points.colwise().minCoeff();
  // A flat box still has a spacing: measure it in the largest extent then.
  const double volume = extent.prod();
  const double h = spacing > 0  ? spacing
                   : volume > 0 ? std::cbrt(volume / double(n))
                                : extent.maxCoeff() / std::cbrt(n);
  BandSamples out;
  const BandTest keep = begin_band(out, samples.values, options, h);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < n; ++i)
    if (keep(samples.values[i])) kept.push_back(i);
  out.samples.points.resize(Eigen::Index(kept.size()), 3);
  out.samples.values.resize(Eigen::Index(kept.size()));
  out.source.resize(kept.size());
  out.core.resize(kept.size());
  for (std::size_t r = 0; r < kept.size(); ++r) {
    out.samples.points.row(Eigen::Index(r)) = samples.points.row(kept[r]);
    out.samples.values[Eigen::Index(r)] = samples.values[kept[r]];
    out.core[r] = keep.core(samples.values[kept[r]]);
    out.source[r] = long(kept[r]);
  }
  require_usable(out, options);
  return out;
}

}  // namespace sdfcontour
