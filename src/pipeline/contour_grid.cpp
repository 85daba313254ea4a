// contour_grid (sdfcontour.h): the common case as one call, on top of contour().
#include <cmath>
#include <cstdio>

#include "pipeline/pipeline_stages.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/sdfcontour.h"

namespace sdfcontour {

namespace {

ContourOptions options_of(const GridSettings& settings) {
  ContourOptions options;
  options.method = parse_method(settings.method);
  if (options.method == Method::Gtcp)
    throw Error("method gtcp needs the exact surface: give contour() an AnalyticShape");
  if (!(settings.adaptivity >= 0) || !std::isfinite(settings.adaptivity))
    throw Error("adaptivity must be a non-negative number of spacings");
  options.adaptivity.tolerance = settings.adaptivity;
  if (std::isnan(settings.truncation)) throw Error("truncation must be a number");
  if (settings.truncation == 0) {
    options.band.truncation_mode = TruncationMode::None;
  } else if (settings.truncation > 0) {
    options.band.truncation_mode = TruncationMode::Given;
    options.band.truncation = settings.truncation;
  }
  if (settings.progress)
    options.progress = [](const std::string& m) {
      std::fprintf(stderr, "[sdfcontour] %s\n", m.c_str());
    };
  return options;
}

template <class T>
Mesh contour_values(const T* values, const std::array<int, 3>& dims, const Bounds& bounds,
                    double isovalue, const GridSettings& settings) {
  if (!values) throw Error("contour_grid: no values");
  if (!std::isfinite(isovalue)) throw Error("contour_grid: the isovalue must be finite");
  GridInput input;
  input.view.dims = dims;
  input.view.bounds = bounds;
  validate_grid_geometry(input.view);
  input.view.type = std::is_same_v<T, float> ? ScalarType::Float32 : ScalarType::Float64;
  input.view.data = values;
  if (isovalue != 0)  // the level's distances, in the caller's precision
    input = detail::mapped_grid(input.view, [isovalue](double v) { return v - isovalue; });
  ContourResult result = contour(input, nullptr, options_of(settings));
  if (!result.mesh || result.mesh->triangles.rows() == 0)
    throw Error("no surface: the " + settings.method + " mesh is empty");
  return std::move(*result.mesh);
}

}  // namespace

Mesh contour_grid(const float* values, const std::array<int, 3>& dims, const Bounds& bounds,
                  double isovalue, const GridSettings& settings) {
  return contour_values(values, dims, bounds, isovalue, settings);
}

Mesh contour_grid(const double* values, const std::array<int, 3>& dims, const Bounds& bounds,
                  double isovalue, const GridSettings& settings) {
  return contour_values(values, dims, bounds, isovalue, settings);
}

}  // namespace sdfcontour
