// Internal: the iso-surface of chi, by marching cubes on finest-depth cells: all active cells at
// the finest depth, and the finest-depth subcells of coarser leaves whose corners straddle the
// iso-value, closed under "a face with a sign change has a cell on its other side". Every node
// value comes from one canonical evaluation, so cells sharing an edge share its vertex: the mesh
// is watertight.
#pragma once

#include <functional>

#include "reconstruction/poisson/indicator.h"
#include "reconstruction/poisson/points.h"
#include "sdfcontour/types.h"

namespace sdfcontour::poisson {

/// The surface chi = iso, outward (chi < iso outside), in the input's units (via frame).
/// `cancel` (optional) is checked as the surface cells are gathered (throws Cancelled).
/// With `along_edges` (chi at any unit-cube point, quadratic along each finest edge: degree-2
/// elements), a vertex is the root of the quadratic through the edge's two node values and chi at
/// its midpoint; otherwise linear interpolation, exact for trilinear chi.
Mesh extract_iso_surface(const Indicator& chi, double iso, const UnitPoints& frame,
                         const std::atomic<bool>* cancel = nullptr,
                         const std::function<double(const Eigen::Vector3d&)>& along_edges = {});

}  // namespace sdfcontour::poisson
