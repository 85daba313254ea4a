#include "sdfcontour/input/samples.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

#include "input/windowed_passes.h"
#include "sdfcontour/input/coordinates.h"

namespace sdfcontour {

Eigen::Vector3d GridGeometry::spacing() const {
  Eigen::Vector3d h;
  const std::array<int, 3> n = whole_dims();
  for (int a = 0; a < 3; ++a) h[a] = (bounds.max[a] - bounds.min[a]) / (n[std::size_t(a)] - 1);
  return h;
}

Eigen::Vector3d GridGeometry::point(int i, int j, int k) const {
  const Eigen::Vector3d h = spacing();
  i += first[0], j += first[1], k += first[2];
  return bounds.min + Eigen::Vector3d(i * h[0], j * h[1], k * h[2]);
}

Samples Grid::to_samples() const {
  Samples s;
  s.points.resize(Eigen::Index(size()), 3);
  s.values = values;
  for (int i = 0; i < dims[0]; ++i)
    for (int j = 0; j < dims[1]; ++j)
      for (int k = 0; k < dims[2]; ++k) s.points.row(Eigen::Index(index(i, j, k))) = point(i, j, k);
  return s;
}

// Larger values would overflow the squared weights and the predicates' filters.
constexpr double kLargestValue = 1e100;

static void require_finite(const Eigen::VectorXd& values, const char* what) {
  for (Eigen::Index i = 0; i < values.size(); ++i)
    if (!(std::abs(values[i]) <= kLargestValue))
      throw Error(std::string(what) +
                  " contain a NaN, infinite or too large (over 1e100) value "
                  "(at index " +
                  std::to_string(i) + ")");
}

GridView view_of(const Grid& grid) {
  GridView v;
  v.dims = grid.dims;
  v.bounds = grid.bounds;
  v.data = grid.values.data();
  v.type = ScalarType::Float64;
  return v;
}

namespace {

// The first non-finite value's index, or n: chunks in parallel, the smallest index wins
// (windows of a mapped grid dropped behind the pass).
template <class T>
std::size_t first_non_finite(const T* f, std::size_t n,
                             const std::function<void(const void*, std::size_t)>* drop_pages) {
  return detail::windowed_reduce(
      drop_pages, f, n, n,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
        // Blocks tested branch-free in the values' own type (vectorised; every finite float is
        // within the limit), and only a block with a bad value searched.
        constexpr std::size_t kBlock = 1024;
        const T limit =
            std::is_same_v<T, float> ? std::numeric_limits<float>::max() : T(kLargestValue);
        auto bad = [limit](T x) { return !(std::abs(x) <= limit); };
        for (std::size_t b = r.begin(); b < r.end() && b < found; b += kBlock) {
          const std::size_t e = std::min(r.end(), b + kBlock);
          int any = 0;
          for (std::size_t i = b; i < e; ++i) any |= bad(f[i]);
          if (any == 0) continue;
          for (std::size_t i = b; i < e && i < found; ++i)
            if (bad(f[i])) return i;
        }
        return found;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); },
      [&](std::size_t found) { return found < n; });
}

}  // namespace

std::optional<std::array<int, 3>> first_non_finite(const GridView& grid) {
  const std::size_t bad =
      grid.visit([&](const auto* f) { return first_non_finite(f, grid.size(), grid.drop_pages); });
  if (bad == grid.size()) return std::nullopt;
  // Named by its (i, j, k), as the user's array indexes it (C order), in its whole grid.
  const std::size_t nz = std::size_t(grid.dims[2]), nyz = std::size_t(grid.dims[1]) * nz;
  return std::array<int, 3>{grid.first[0] + int(bad / nyz), grid.first[1] + int(bad % nyz / nz),
                            grid.first[2] + int(bad % nz)};
}

void validate_grid_geometry(const GridGeometry& grid) {
  for (int a = 0; a < 3; ++a)
    if (grid.dims[a] < 2)
      throw Error("grid has " + std::to_string(grid.dims[a]) +
                  " samples along an axis; at least 2 are needed on each axis");
  for (int a = 0; a < 3; ++a)
    if (!(grid.bounds.min[a] < grid.bounds.max[a]))
      throw Error("bounds must have min < max on every axis");
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(grid.bounds.min[a]) <= kLargestCoordinate &&
          std::abs(grid.bounds.max[a]) <= kLargestCoordinate))
      throw Error("bounds must be finite and at most 1e30 in size on every axis");
}

void validate_grid(const GridView& grid) {
  validate_grid_geometry(grid);
  if (grid.values_checked) return;
  if (const auto at = first_non_finite(grid))
    throw Error("grid values contain a NaN, infinite or too large (over 1e100) value (at [" +
                std::to_string((*at)[0]) + ", " + std::to_string((*at)[1]) + ", " +
                std::to_string((*at)[2]) + "])");
}

void validate_grid(const Grid& grid) {
  if (std::size_t(grid.values.size()) != grid.size())
    throw Error("grid values do not match its dimensions");
  validate_grid(view_of(grid));
}

void require_sign_change(const GridView& grid) {
  const auto [inside, outside] = grid.visit([&](const auto* f) {
    return detail::windowed_reduce(
        grid.drop_pages, f, grid.size(), std::pair<bool, bool>{},
        [&](const tbb::blocked_range<std::size_t>& r, std::pair<bool, bool> s) {
          for (std::size_t i = r.begin(); i < r.end() && !(s.first && s.second); ++i)
            (f[i] < 0 ? s.first : s.second) = true;
          return s;
        },
        [](std::pair<bool, bool> a, std::pair<bool, bool> b) {
          return std::pair<bool, bool>{a.first || b.first, a.second || b.second};
        },
        [](std::pair<bool, bool> s) { return s.first && s.second; });
  });
  if (!(inside && outside))
    throw Error(std::string("no surface: every value is ") +
                (inside ? "negative" : "non-negative") + ", so the field has no sign change");
}

void validate_samples(const Samples& samples) {
  if (samples.points.rows() != samples.values.size())
    throw Error("samples have " + std::to_string(samples.points.rows()) + " points but " +
                std::to_string(samples.values.size()) + " values");
  if (samples.points.rows() < 4)
    throw Error("need at least 4 samples, got " + std::to_string(samples.points.rows()));
  for (Eigen::Index i = 0; i < samples.points.rows(); ++i)
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(samples.points(i, a)) <= kLargestValue))
        throw Error(
            "sample positions contain a NaN, infinite or too large (over 1e100) value "
            "(at row " +
            std::to_string(i) + ")");
  require_finite(samples.values, "sample values");
}

void require_sign_change(const Eigen::VectorXd& values) {
  bool inside = false, outside = false;
  for (Eigen::Index i = 0; i < values.size(); ++i) (values[i] < 0 ? inside : outside) = true;
  if (!(inside && outside))
    throw Error(std::string("no surface: every value is ") +
                (inside ? "negative" : "non-negative") + ", so the field has no sign change");
}

}  // namespace sdfcontour
