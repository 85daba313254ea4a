// sdfcontour.h's calls: one per kind of input, each on top of contour().
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "pipeline/pipeline_stages.h"
#include "sdfcontour/io/vdb.h"
#include "sdfcontour/pipeline/option_ranges.h"
#include "sdfcontour/pipeline/pipeline.h"
#include "sdfcontour/sdfcontour.h"

namespace sdfcontour {

namespace {

std::function<void(const std::string&)> progress_on_stderr(bool on) {
  if (!on) return nullptr;
  return [](const std::string& m) { std::fprintf(stderr, "[sdfcontour] %s\n", m.c_str()); };
}

void check_adaptivity(double adaptivity) {
  if (!(adaptivity >= 0) || !std::isfinite(adaptivity))
    throw Error("adaptivity must be a non-negative number of spacings");
}

Mesh mesh_of(ContourResult result, const std::string& method) {
  if (!result.mesh || result.mesh->triangles.rows() == 0)
    throw Error("no surface: the " + method + " mesh is empty");
  return std::move(*result.mesh);
}

ContourOptions options_of(const GridSettings& settings) {
  ContourOptions options;
  options.method = parse_method(settings.method);
  if (options.method == Method::Gtcp)
    throw Error(
        "method gtcp needs the exact surface: give contour_with_exact_sdf() an AnalyticShape");
  check_adaptivity(settings.adaptivity);
  options.adaptivity.tolerance = settings.adaptivity;
  if (std::isnan(settings.truncation)) throw Error("truncation must be a number");
  if (settings.truncation == 0) {
    options.band.truncation_mode = TruncationMode::None;
  } else if (settings.truncation > 0) {
    options.band.truncation_mode = TruncationMode::Given;
    options.band.truncation = settings.truncation;
  }
  options.progress = progress_on_stderr(settings.progress);
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
  return mesh_of(contour(input, options_of(settings)), settings.method);
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

Mesh contour_function(const std::function<double(const Eigen::Vector3d&)>& f,
                      const std::array<int, 3>& dims, const Bounds& bounds, double isovalue,
                      const GridSettings& settings) {
  if (!f) throw Error("contour_function: no function");
  GridGeometry geometry;
  geometry.dims = dims;
  geometry.bounds = bounds;
  validate_grid_geometry(geometry);
  const Eigen::Vector3d h = geometry.spacing();
  std::vector<double> values(geometry.size());
  tbb::parallel_for(0, dims[0], [&](int i) {
    for (int j = 0; j < dims[1]; ++j)
      for (int k = 0; k < dims[2]; ++k) {
        const Eigen::Vector3d p = bounds.min + Eigen::Vector3d(i, j, k).cwiseProduct(h);
        const double v = f(p);
        if (!std::isfinite(v)) {
          std::ostringstream m;
          m << "contour_function: the function is not finite at (" << p[0] << ", " << p[1] << ", "
            << p[2] << ")";
          throw Error(m.str());
        }
        values[(std::size_t(i) * std::size_t(dims[1]) + std::size_t(j)) * std::size_t(dims[2]) +
               std::size_t(k)] = v;
      }
  });
  return contour_values(values.data(), dims, bounds, isovalue, settings);
}

Mesh contour_samples(const PointMatrix& points, const Eigen::VectorXd& values,
                     const SampleSettings& settings) {
  if (points.rows() != values.size())
    throw Error("contour_samples: " + std::to_string(points.rows()) + " points but " +
                std::to_string(values.size()) + " values");
  ContourOptions options;
  options.method = parse_method(settings.method);
  if (options.method == Method::Mc)
    throw Error("method mc needs a grid: give scattered samples gcp, mt-rt or mt-dt");
  if (options.method == Method::Gtcp)
    throw Error(
        "method gtcp needs the exact surface: give contour_with_exact_sdf() an AnalyticShape");
  if (settings.depth != 0) require_in_range("--depth", settings.depth, "depth");
  options.poisson.depth = settings.depth;
  check_adaptivity(settings.adaptivity);
  options.adaptivity.tolerance = settings.adaptivity;
  options.progress = progress_on_stderr(settings.progress);
  ScatteredInput input{Samples{points, values}, 0.0};
  return mesh_of(contour(input, options), settings.method);
}

Mesh contour_vdb(const std::string& path, const GridSettings& settings,
                 const std::string& grid_name) {
  ContourOptions options = options_of(settings);
  // Marching cubes and GCP's local reconstruction read the level set a block at a time; the
  // triangulations take its active voxels as scattered samples.
  if (options.method == Method::Mc || options.method == Method::Gcp) {
    VdbLayout layout;
    BlockedGrid grid = vdb_blocked_grid(path, grid_name, &layout);
    BlockedGridInput input{std::move(grid), layout.background, vdb_world_from_grid(layout)};
    return mesh_of(contour(input, options), settings.method);
  }
  VdbLevelSet level_set = read_vdb_level_set(path, grid_name);
  if (options.band.truncation_mode == TruncationMode::Auto && level_set.background > 0) {
    options.band.truncation_mode = TruncationMode::Given;
    options.band.truncation = level_set.background;
  }
  ScatteredInput input{std::move(level_set.samples), level_set.voxel_size};
  return mesh_of(contour(input, options), settings.method);
}

}  // namespace sdfcontour
