#include "sdfcontour/band.h"

#include <cmath>
#include <string>

namespace sdfcontour {

namespace {

// Values within this relative distance of a truncation value count as truncated: writers
// store T in float32 and may round it.
constexpr double kTruncationTolerance = 1e-6;
// Fewer samples at a sign's extreme than this are a coincidence (a grid's corners, a centre).
constexpr long kMinTruncatedSamples = 64;

// Keep sample i when it lies in the band and carries a distance.
struct BandTest {
  double limit;  // band * h
  Truncation truncation;
  bool operator()(double v) const { return std::abs(v) <= limit && !truncation.truncated(v); }
};

BandTest make_test(const Eigen::VectorXd& values, const BandOptions& options, double h,
                   BandSamples& out) {
  validate_band_options(options);
  out.spacing = h;
  out.truncation = resolve_truncation(values, options);
  out.input_count = long(values.size());
  return {options.band * h, out.truncation};
}

void require_usable(const BandSamples& b, const BandOptions& options) {
  const Eigen::Index n = b.samples.values.size();
  bool inside = false, outside = false;
  for (Eigen::Index i = 0; i < n; ++i) (b.samples.values[i] < 0 ? inside : outside) = true;
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

Truncation detect_truncation(const Eigen::VectorXd& values, double min_fraction) {
  double most_negative = 0, most_positive = 0;
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    most_negative = std::min(most_negative, values[i]);
    most_positive = std::max(most_positive, values[i]);
  }
  long at_inside = 0, at_outside = 0, negatives = 0;
  const double lo = -most_negative * (1 - kTruncationTolerance),
               hi = most_positive * (1 - kTruncationTolerance);
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    negatives += values[i] < 0;
    if (values[i] < 0 && -values[i] >= lo) ++at_inside;
    if (values[i] > 0 && values[i] >= hi) ++at_outside;
  }
  auto clamped = [&](long at_extreme, long of_sign) {
    return at_extreme >= kMinTruncatedSamples && double(at_extreme) >= min_fraction * double(of_sign);
  };
  Truncation t;
  if (most_negative < 0 && clamped(at_inside, negatives)) t.inside = -most_negative;
  if (most_positive > 0 && clamped(at_outside, long(values.size()) - negatives))
    t.outside = most_positive;
  return t;
}

Truncation resolve_truncation(const Eigen::VectorXd& values, const BandOptions& options) {
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

void validate_band_options(const BandOptions& options) {
  if (!(options.band > 0))
    throw Error("the band must be a positive number of spacings (or 'all'), got " +
                std::to_string(options.band));
  if (options.truncation_mode == TruncationMode::Given &&
      !(options.truncation > 0 && std::isfinite(options.truncation)))
    throw Error("the truncation distance must be positive and finite");
}

BandSamples select_band(const Grid& grid, const BandOptions& options) {
  BandSamples out;
  const BandTest keep = make_test(grid.values, options, grid.spacing().maxCoeff(), out);
  const auto& f = grid.values;
  long count = 0;
  for (Eigen::Index p = 0; p < f.size(); ++p) count += keep(f[p]);
  out.samples.points.resize(count, 3);
  out.samples.values.resize(count);
  out.source.resize(std::size_t(count));
  Eigen::Index at = 0;
  for (int i = 0; i < grid.dims[0]; ++i)
    for (int j = 0; j < grid.dims[1]; ++j)
      for (int k = 0; k < grid.dims[2]; ++k) {
        const std::size_t p = grid.index(i, j, k);
        if (!keep(f[Eigen::Index(p)])) continue;
        out.samples.points.row(at) = grid.point(i, j, k).transpose();
        out.samples.values[at] = f[Eigen::Index(p)];
        out.source[std::size_t(at++)] = long(p);
      }
  require_usable(out, options);
  return out;
}

BandSamples select_band(const Samples& samples, const BandOptions& options) {
  const Eigen::Index n = samples.points.rows();
  const Eigen::Vector3d extent =
      samples.points.colwise().maxCoeff() - samples.points.colwise().minCoeff();
  // A flat box still has a spacing: measure it in the largest extent then.
  const double volume = extent.prod();
  const double h = volume > 0 ? std::cbrt(volume / double(n)) : extent.maxCoeff() / std::cbrt(n);
  BandSamples out;
  const BandTest keep = make_test(samples.values, options, h, out);
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < n; ++i)
    if (keep(samples.values[i])) kept.push_back(i);
  out.samples.points.resize(Eigen::Index(kept.size()), 3);
  out.samples.values.resize(Eigen::Index(kept.size()));
  out.source.resize(kept.size());
  for (std::size_t r = 0; r < kept.size(); ++r) {
    out.samples.points.row(Eigen::Index(r)) = samples.points.row(kept[r]);
    out.samples.values[Eigen::Index(r)] = samples.values[kept[r]];
    out.source[r] = long(kept[r]);
  }
  require_usable(out, options);
  return out;
}

}  // namespace sdfcontour
