// Internal: the chord offsets that the projection gives its vertices (contact_projection.cpp), kept
// so that a split can set them again for the smaller triangles it makes and the carving can leave
// them in place (lattice_subdivision.cpp, sphere_carving.cpp).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "reconstruction/carving_internal.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// A fit's points lie on its quadric to within this many spacings (weighted RMS) where the surface
// is smooth at the spacing's scale. There the chord offset is the flat triangles' true sag and is
// kept. The polyhedral meshes' grids miss their quadrics by more at nearly every vertex: their
// meshes are the same to 0.1% with it (the 17 shared meshes at 64^3), while exact spheres and tori
// come 0.56-0.67x as far at 64^3 (docs/scale.md).
constexpr double kSmoothFitRms = 1e-3;

struct ChordOffsets {
  /// Per vertex, the chord offset that the projection added along its normal, in spacings (0: none
  /// or not smooth), with the normal and the fitted quadric's second-order part as a symmetric
  /// form on edges in spacings (xx, xy, xz, yy, yz, zz): a flat triangle with edges e lies
  /// sum_e e^T Q e / 12 off the quadric on average.
  std::vector<double> offset;
  std::vector<Eigen::Vector3d> normal;
  std::vector<std::array<double, 6>> form;

  void resize(std::size_t n) {
    offset.assign(n, 0.0);
    normal.assign(n, Eigen::Vector3d::Zero());
    form.assign(n, std::array<double, 6>{});
  }
  std::size_t size() const { return offset.size(); }
};

// Per vertex, the sum over its triangles of e e^T over their three edges e (in spacings), and
// the number of triangles: a flat triangle with its corners on z(x, y) lies
// sum_e Q(e) / 12 above it on average, Q the quadric's quadratic part, so the vertex's chord
// offset is minus the mean of that over its triangles. Made only where a vertex's fit asks for
// it, from its own triangles: an array of every triangle's sums, made first, was 3% of a 512^3
// run, most of it faulting its pages in.
class EdgeMoments {
 public:
  EdgeMoments(const Mesh& mesh, const VertexTriangles& around, double spacing)
      : mesh_(mesh), around_(around), spacing_(spacing) {}

  // Vertex v's triangles: their count, and the sum of their moments in ascending order (each
  // triangle's three edges summed first).
  int triangles(Eigen::Index v) const {
    return around_.offsets[std::size_t(v) + 1] - around_.offsets[std::size_t(v)];
  }
  Eigen::Matrix3d sum(Eigen::Index v) const {
    Symmetric sum{};
    for (int o = around_.offsets[std::size_t(v)]; o < around_.offsets[std::size_t(v) + 1]; ++o) {
      const Eigen::Index t = around_.triangles[std::size_t(o)];
      Symmetric e2{};
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = (mesh_.vertices.row(mesh_.triangles(t, (k + 1) % 3)) -
                                   mesh_.vertices.row(mesh_.triangles(t, k)))
                                      .transpose() /
                                  spacing_;
        for (int u = 0; u < 6; ++u) e2[std::size_t(u)] += e[kRow[u]] * e[kColumn[u]];
      }
      for (int u = 0; u < 6; ++u) sum[std::size_t(u)] += e2[std::size_t(u)];
    }
    Eigen::Matrix3d m;
    for (int u = 0; u < 6; ++u)
      m(kRow[u], kColumn[u]) = m(kColumn[u], kRow[u]) = sum[std::size_t(u)];
    return m;
  }

 private:
  using Symmetric = std::array<double, 6>;  // (0,0), (0,1), (0,2), (1,1), (1,2), (2,2)
  static constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kColumn[6] = {0, 1, 2, 1, 2, 2};
  const Mesh& mesh_;
  const VertexTriangles& around_;
  double spacing_;
};

// The chord offset (in spacings) of a vertex whose triangles' edge moments (sum of e e^T over their
// edges, in spacings) are `moments`, over `triangles` triangles, for the form `q`.
inline double chord_offset(const std::array<double, 6>& q, const Eigen::Matrix3d& moments,
                           int triangles) {
  const double sum = q[0] * moments(0, 0) + 2 * q[1] * moments(0, 1) + 2 * q[2] * moments(0, 2) +
                     q[3] * moments(1, 1) + 2 * q[4] * moments(1, 2) + q[5] * moments(2, 2);
  return -sum / 12 / triangles;
}

}  // namespace sdfcontour::detail
