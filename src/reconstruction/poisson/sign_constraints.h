// Internal: making chi agree with samples whose side of the surface is known. The screened
// Poisson solve fits the contact points and normals in a least-squares sense, so next to the
// surface a grid sample can end on the wrong side of the mesh (2-40 per shared mesh at 32^3, up
// to 0.4 h deep) although its value says which side it is on. Each such sample is a linear
// inequality on chi's node values around it; projecting onto the violated ones (Kaczmarz) moves
// chi only where it disagrees with the data.
#pragma once

#include "reconstruction/poisson/indicator.h"
#include "reconstruction/poisson/points.h"
#include "sdfcontour/reconstruction/poisson.h"

namespace sdfcontour::poisson {

struct SignCorrection {
  long violations = 0;       ///< samples that disagreed with chi before any correction
  long violations_left = 0;  ///< after the last sweep
  int sweeps = 0;
};

/// Corrects chi's node values so that every sample of `sides` (in the input's units; `frame`
/// maps them to the unit cube) lies on its side: chi >= iso + m inside, chi <= iso - m outside,
/// with m = margin * |value| * |grad chi| (unit-cube units, measured once on the solved chi). A
/// violated sample is met exactly by a smooth bump of options.radius around it (radius 0: the
/// least change of its cell's corner values). Samples are visited in order, sweep after sweep,
/// until none is violated or max_sweeps.
SignCorrection enforce_signs(Indicator& chi, double iso, const SignedSamples& sides,
                             const UnitPoints& frame, const SignConstraintOptions& options);

}  // namespace sdfcontour::poisson
