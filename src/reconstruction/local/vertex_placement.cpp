#include "reconstruction/local/vertex_placement.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace sdfcontour::detail {

namespace {

// A vertex stays this fraction of its cell inside it. On the cell's side (clamped there, or the
// planes' centroid on a grid line), the vertices of two cells next to a feature could meet (1 ulp
// apart on the cube at 128^3): their triangles then overlap, and neither the crossing test nor
// the untangling sees it. It moves along the directions the planes leave free where it can (so
// vertices of a linear field stay on its plane), else straight in. Measured (bench/local.py,
// gcp-local): the cube at 128^3 67 crossing pairs -> 0 (L1 1.23x -> 1.33x MC's, sharp edges 0.34 h
// -> 0.27 h), the built-in box at 48^3-64^3 80 -> 0; every other shared mesh at 32^3 and 64^3 (and
// seven at 128^3) within 1.5% of its L1 (plane 32^3: 1.5% lower), the geometric means unchanged
// (0.379x and 0.365x MC's).
constexpr double kCellMargin = 1e-3;

// Points this many spacings apart are one point (a corner's contact points, from any side).
constexpr double kSamePoint = 1e-9;

// Where three or more of the planes' points coincide (to kSamePoint h) with normals that span every
// direction, samples on different sides of a corner touch the surface at that one point (a
// smooth surface is touched at one point only along one normal): the corner itself. The largest
// such cluster (ties by position), or nothing.
bool shared_corner(const std::vector<TangentPlane>& planes, double feature_ratio, double h,
                   Eigen::Vector3d& corner) {
  int best = 0;
  for (std::size_t a = 0; a < planes.size(); ++a) {
    Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
    int count = 0;
    for (const TangentPlane& t : planes)
      if ((t.point - planes[a].point).norm() <= kSamePoint * h) {
        spread += t.normal * t.normal.transpose();
        ++count;
      }
    if (count < 3 || count < best) continue;
    const Eigen::Vector3d lambda =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues();
    if (!(lambda[0] > feature_ratio * lambda[2])) continue;
    if (count == best &&
        !std::lexicographical_compare(planes[a].point.data(), planes[a].point.data() + 3,
                                      corner.data(), corner.data() + 3))
      continue;
    best = count;
    corner = planes[a].point;
  }
  return best > 0;
}

constexpr double kCornerEdgeMiss = 1e-3, kCornerEdgeShare = 0.1, kCornerEdgeNear = 1e-2;

}  // namespace

VertexResult place_vertex(const std::vector<TangentPlane>& planes,
                          const std::vector<TangentPlane>& crossings, const Eigen::Vector3d& lo,
                          const Eigen::Vector3d& hi, double h,
                          const LocalReconstructionOptions& options) {
  VertexResult out;
  out.from_crossings = int(planes.size()) < options.min_points;
  QuadricSolution s;
  if (!out.from_crossings && shared_corner(planes, options.feature_ratio, h, s.position)) {
    s.rank = 3;
    s.free.setZero();
    out.corner = true;
  } else {
    s = minimise_quadric(out.from_crossings ? crossings : planes, options.feature_ratio,
                         options.robust_rounds, options.robust_scale * h);
  }
  out.feature = s.rank >= 2;
  const Eigen::Vector3d margin = kCellMargin * (hi - lo);
  const Eigen::Vector3d inner_lo = lo + margin, inner_hi = hi - margin;
  out.clamped = s.position != s.position.cwiseMax(lo).cwiseMin(hi);
  // Into the cell shrunk by the margin, along the directions the planes leave free where they
  // suffice (the quadric's minimum stays: a plane's vertices stay on it), else straight.
  Eigen::Vector3d x = s.position;
  for (int round = 0; round < 8; ++round) {
    const Eigen::Vector3d inside = x.cwiseMax(inner_lo).cwiseMin(inner_hi);
    if (inside == x) break;
    x += s.free * (inside - x);
  }
  const bool in_cell = (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
  if (in_cell) out.fitted = x;
  out.position = in_cell && !out.clamped ? x : s.position.cwiseMax(inner_lo).cwiseMin(inner_hi);
  if (options.narrow_cells && s.rank == 1 && !out.from_crossings) {
    // A narrow cell's smooth patch (narrow_cells): its few points' centroid is no place in the
    // cell, so the mean of its edge crossings goes onto their plane (dual contouring's mass
    // point; the analytic sphere at 64^3: L1 0.000213 h -> 0.000157 h), else the minimum slides
    // along the plane into the cell, where the plane crosses it.
    Eigen::Vector3d onto = Eigen::Vector3d::Constant(NAN);
    if (!crossings.empty()) {
      Eigen::Vector3d mass = Eigen::Vector3d::Zero();
      for (const TangentPlane& c : crossings) mass += c.point;
      mass /= double(crossings.size());
      onto = mass + (Eigen::Matrix3d::Identity() - s.free) * (s.position - mass);
    }
    if ((onto.array() >= lo.array()).all() && (onto.array() <= hi.array()).all()) {
      out.position = onto.cwiseMax(inner_lo).cwiseMin(inner_hi);
      out.clamped = false;
    } else if (out.clamped && in_cell) {
      out.position = x;
      out.clamped = false;
    }
  }
  if (options.edge_fans && out.clamped && !in_cell && !out.corner && !out.from_crossings &&
      !crossings.empty()) {
    // No minimum lies in the cell, a feature beyond it whose planes reach in: the cell may hold
    // only slivers of the feature's faces. The quadric's least point where the cell's surface is,
    // the box of its edge crossings (within_crossings).
    Eigen::Vector3d box_lo = crossings[0].point, box_hi = box_lo;
    for (const TangentPlane& c : crossings)
      box_lo = box_lo.cwiseMin(c.point), box_hi = box_hi.cwiseMax(c.point);
    box_lo = box_lo.cwiseMax(inner_lo).cwiseMin(inner_hi);
    box_hi = box_hi.cwiseMax(box_lo).cwiseMin(inner_hi);
    out.crossings_box = CrossingsBox{box_lo, box_hi};
  }
  if (out.corner && out.position != s.position) out.corner_beyond = s.position;
  out.corner = out.corner && out.position == s.position;
  return out;
}

Eigen::Vector3d within_crossings(const std::vector<TangentPlane>& planes, const CrossingsBox& box,
                                 double h, const LocalReconstructionOptions& options) {
  return minimise_quadric_in_box(planes, box.lo, box.hi, options.robust_rounds,
                                 options.robust_scale * h);
}

std::optional<VertexResult> corner_edge_vertex(const std::vector<TangentPlane>& wide,
                                               const Eigen::Vector3d& corner,
                                               const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                               double h,
                                               const LocalReconstructionOptions& options) {
  std::vector<TangentPlane> rest;
  for (const TangentPlane& t : wide)
    if ((t.point - corner).norm() > kSamePoint * h) rest.push_back(t);
  if (int(rest.size()) < options.min_points) return std::nullopt;
  const Eigen::Vector3d margin = kCellMargin * (hi - lo);
  VertexResult out;
  out.position = minimise_quadric_in_box(rest, lo + margin, hi - margin, options.robust_rounds,
                                         options.robust_scale * h);
  // Only where a share of those planes passes through it (faces that meet at the corner: on the
  // built-in box at 40^3, band 3, 17-63% within 1e-3 h): on a mesh's small facets the point is a
  // compromise that no plane passes (at most 2% of them on armadillo, penguin, plane, cat at
  // 32^3 and 64^3, where the crossings did better: armadillo 64^3 1.6% higher L1 with the point).
  // And the planes within kCornerEdgeNear of it make an edge (normals in two directions at least):
  // a cell on one face keeps its own vertex (the built-in box at 32^3: three face vertices 2e-4 h
  // off with it). At 1e-3 h (kCornerEdgeMiss) the box at 40^3 lost 13 of its 17 edge vertices.
  long through = 0;
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const TangentPlane& t : rest) {
    const double miss = std::abs(t.normal.dot(out.position - t.point));
    through += miss <= kCornerEdgeMiss * h;
    if (miss <= kCornerEdgeNear * h) spread += t.normal * t.normal.transpose();
  }
  if (!(double(through) >= kCornerEdgeShare * double(rest.size()))) return std::nullopt;
  const Eigen::Vector3d lambda =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues();
  if (!(lambda[1] > options.feature_ratio * lambda[2])) return std::nullopt;
  out.feature = true;
  return out;
}

}  // namespace sdfcontour::detail
