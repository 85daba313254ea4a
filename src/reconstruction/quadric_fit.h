// Internal: the projection's fit of a quadric height field to the contact points near a vertex
// (contact_projection.cpp).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "sdfcontour/reconstruction/contact_projection.h"

namespace sdfcontour::detail {

// z(x, y) = c . (1, x, y, x^2, xy, y^2): a vertex's neighbourhood as heights over its tangent
// plane, in spacings.
using Coefficients = Eigen::Matrix<double, 6, 1>;
struct FitRow {
  Coefficients row;
  double z, w;
  Eigen::Vector3d normal;  // the point's unit normal in the tangent frame (a, b, n)
};

// 1 / (2 sin(normal_turn_scale / 2))^2, so that a turn's squared chord times it is about
// (turn / normal_turn_scale)^2; 0 where the turns weigh nothing.
double inverse_turn_chord2(const ContactProjectionOptions& o);

// Weighted least squares, then robust_rounds refits with each row's weight divided by
// 1 + (its miss / robust_scale)^2; with normal_turn_scale, every fit also divides it by
// 1 + (its normal's turn from the fit's / normal_turn_scale)^2, the turn measured by its chord,
// from the vertex's normal in the first fit (the built-in box at 32^3: vertices next to its
// edges 0.146 h inside a face at worst without the turns, 0.085 h with them). False where the
// rows give no reliable height at the vertex: a rank-deficient or one-sided neighbourhood
// (max_variance_factor), or points too far from any quadric (max_residual). The first fit's
// spread is judged without the turns: where the surface curves within the radius, its points
// turn from the vertex's normal for good reason (a cylinder of radius 4 h: 19 degrees 1.4 h
// away), and the next fit gives them their weight back. `inv_chord_scale2`: inverse_turn_chord2(o).
bool fit_quadric(const std::vector<FitRow>& fit, const ContactProjectionOptions& o,
                 double inv_chord_scale2, Coefficients& c);

}  // namespace sdfcontour::detail
