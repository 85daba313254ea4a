// Built-in analytic shapes with exact signed distances and exact gradients: the embedded
// examples and the test fixtures. Their gradients give ground-truth contact points (GTCP).
// Sampling any signed distance (a grid, a truncated grid, random points): signed_distance.h.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sdfcontour/input/samples.h"
#include "sdfcontour/input/signed_distance.h"

namespace sdfcontour {

/// Names of the built-in shapes: sphere, torus, box, plate, shell, csg.
std::vector<std::string> builtin_shape_names();

/// The built-in shape `name`; throws Error for an unknown name.
///  - sphere: radius 0.6 at the origin.
///  - torus: major radius 0.55, minor radius 0.25, around the z axis.
///  - box: half-extents (0.6, 0.45, 0.35), sharp edges and corners.
///  - plate: a thin box, half-extents (0.7, 0.5, 0.06).
///  - shell: a hollow sphere, radii 0.55 and 0.65 (a thin shell, two sheets).
///  - csg: union of two overlapping spheres, with a concave crease circle where they meet.
std::unique_ptr<AnalyticShape> make_builtin_shape(const std::string& name);

/// A parsed `builtin:NAME@N` (an N^3 grid) or `builtin:NAME@random:COUNT` specification.
struct BuiltinSpec {
  std::string name;
  bool random = false;
  int resolution = 0;     ///< grid samples per axis, when !random
  std::size_t count = 0;  ///< number of random samples, when random
};

/// True if `text` starts with "builtin:".
bool is_builtin_spec(const std::string& text);
/// Parses a built-in specification; throws Error naming what is wrong.
BuiltinSpec parse_builtin_spec(const std::string& text);

}  // namespace sdfcontour
