#include "contact_points/convex_cell.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sdfcontour::detail {

void ConvexCell::reset(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  lo_ = lo;
  hi_ = hi;
  vertices_.clear();
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d x(c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]);
    // Planes -1/-2: x = lo/hi, -3/-4: y, -5/-6: z; ascending.
    vertices_.push_back({x, {c & 4 ? -6 : -5, c & 2 ? -4 : -3, c & 1 ? -2 : -1}});
  }
  face_vertices_ = {0, 2, 6, 4, 1, 5, 7, 3, 0, 4, 5, 1, 2, 3, 7, 6, 0, 1, 3, 2, 4, 6, 7, 5};
  face_start_ = {0, 4, 8, 12, 16, 20, 24};
  face_plane_ = {-1, -2, -3, -4, -5, -6};
}

namespace {

// The planes that u and w share (up to two), then `id`, ascending: the edge's new vertex.
std::array<int, 3> edge_planes(const std::array<int, 3>& u, const std::array<int, 3>& w, int face,
                               int id) {
  std::array<int, 3> out{face, face, id};
  int n = 0;
  for (int a : u)
    if (n < 2 && std::find(w.begin(), w.end(), a) != w.end()) out[std::size_t(n++)] = a;
  if (n == 1 && out[0] != face) out[1] = face;
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

void ConvexCell::clip(const Eigen::Vector3d& normal, double offset, int id, double tolerance) {
  if (vertices_.empty()) return;
  // Most planes miss the cell: its bounding box tells, and nothing is written for them.
  const Eigen::Vector3d centre = (lo_ + hi_) / 2, extent = (hi_ - lo_) / 2;
  if (normal.dot(centre) + normal.cwiseAbs().dot(extent) - offset <= tolerance) return;
  d_.resize(vertices_.size());
  bool any_out = false, any_in = false;
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    const double d = d_[v] = normal.dot(vertices_[v].point) - offset;
    any_out |= d > tolerance;
    any_in |= d <= tolerance;
  }
  if (!any_out) return;
  if (!any_in) {
    vertices_.clear();
    face_vertices_.clear();
    face_start_.assign(1, 0);
    face_plane_.clear();
    return;
  }
  kept_.clear();
  cap_.clear();
  cut_.clear();
  index_.assign(vertices_.size(), -1);
  for (std::size_t v = 0; v < vertices_.size(); ++v) {
    if (d_[v] > tolerance) continue;
    index_[v] = int(kept_.size());
    if (d_[v] >= -tolerance) cap_.push_back(index_[v]);  // on the plane: on the new face too
    kept_.push_back(vertices_[v]);
  }
  new_vertices_.clear();
  new_start_.assign(1, 0);
  new_plane_.clear();
  for (std::size_t f = 0; f + 1 < face_start_.size(); ++f) {
    const int first = face_start_[f], size = face_start_[f + 1] - first;
    for (int i = 0; i < size; ++i) {
      const int u = face_vertices_[std::size_t(first + i)];
      const int w = face_vertices_[std::size_t(first + (i + 1) % size)];
      if (index_[std::size_t(u)] >= 0) new_vertices_.push_back(index_[std::size_t(u)]);
      const double du = d_[std::size_t(u)], dw = d_[std::size_t(w)];
      if (!((du < -tolerance && dw > tolerance) || (du > tolerance && dw < -tolerance))) continue;
      const int lo = std::min(u, w), hi = std::max(u, w);
      int made = -1;
      for (const auto& c : cut_)
        if (c[0] == lo && c[1] == hi) made = c[2];
      if (made < 0) {
        const Vertex& a = vertices_[std::size_t(u)];
        const Vertex& b = vertices_[std::size_t(w)];
        const double t = du / (du - dw);
        made = int(kept_.size());
        kept_.push_back({a.point + t * (b.point - a.point),
                         edge_planes(a.planes, b.planes, face_plane_[f], id)});
        cut_.push_back({lo, hi, made});
        cap_.push_back(made);
      }
      new_vertices_.push_back(made);
    }
    if (int(new_vertices_.size()) - new_start_.back() >= 3) {
      new_start_.push_back(int(new_vertices_.size()));
      new_plane_.push_back(face_plane_[f]);
    } else {
      new_vertices_.resize(std::size_t(new_start_.back()));
    }
  }
  if (cap_.size() >= 3) {
    // Convex: its vertices in angle order around their centroid.
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int v : cap_) centre += kept_[std::size_t(v)].point;
    centre /= double(cap_.size());
    const Eigen::Vector3d e1 =
        normal
            .cross(std::abs(normal[0]) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY())
            .normalized();
    const Eigen::Vector3d e2 = normal.cross(e1);
    order_.clear();
    for (int v : cap_) {
      const Eigen::Vector3d r = kept_[std::size_t(v)].point - centre;
      order_.emplace_back(std::atan2(r.dot(e2), r.dot(e1)), v);
    }
    std::sort(order_.begin(), order_.end());
    for (const auto& [angle, v] : order_) new_vertices_.push_back(v);
    new_start_.push_back(int(new_vertices_.size()));
    new_plane_.push_back(id);
  }
  vertices_.swap(kept_);
  lo_ = hi_ = vertices_[0].point;
  for (const Vertex& v : vertices_) {
    lo_ = lo_.cwiseMin(v.point);
    hi_ = hi_.cwiseMax(v.point);
  }
  face_vertices_.swap(new_vertices_);
  face_start_.swap(new_start_);
  face_plane_.swap(new_plane_);
}

}  // namespace sdfcontour::detail
