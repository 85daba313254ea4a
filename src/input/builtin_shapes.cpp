#include "sdfcontour/input/builtin_shapes.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "sdfcontour/pipeline/option_ranges.h"

namespace sdfcontour {

namespace {

using Eigen::Vector3d;

// A unit vector orthogonal-ish fallback for gradients at a singular point (sphere centre, say).
const Vector3d kFallbackDirection(0.0, 0.0, 1.0);

Vector3d normalized_or_fallback(const Vector3d& v) {
  const double n = v.norm();
  return n > 0 ? Vector3d(v / n) : kFallbackDirection;
}

class Sphere : public AnalyticShape {
 public:
  Sphere(Vector3d centre, double radius) : c_(centre), r_(radius) {}
  double distance(const Vector3d& p) const override { return (p - c_).norm() - r_; }
  Vector3d gradient(const Vector3d& p) const override { return normalized_or_fallback(p - c_); }

 private:
  Vector3d c_;
  double r_;
};

class Torus : public AnalyticShape {
 public:
  Torus(double major, double minor) : R_(major), r_(minor) {}
  // Distance to the core circle (radius R in the xy plane) minus the tube radius.
  double distance(const Vector3d& p) const override { return (p - core_point(p)).norm() - r_; }
  Vector3d gradient(const Vector3d& p) const override {
    return normalized_or_fallback(p - core_point(p));
  }

 private:
  Vector3d core_point(const Vector3d& p) const {
    const double rho = std::hypot(p.x(), p.y());
    // On the z axis every core point is closest: pick the one along +x.
    const double cx = rho > 0 ? p.x() / rho : 1.0, cy = rho > 0 ? p.y() / rho : 0.0;
    return Vector3d(R_ * cx, R_ * cy, 0.0);
  }
  double R_, r_;
};

class Box : public AnalyticShape {
 public:
  explicit Box(Vector3d half_extents) : b_(half_extents) {}
  double distance(const Vector3d& p) const override {
    const Vector3d q = p.cwiseAbs() - b_;
    const double outside = q.cwiseMax(0.0).norm();
    const double inside = std::min(q.maxCoeff(), 0.0);
    return outside + inside;
  }
  Vector3d gradient(const Vector3d& p) const override {
    const Vector3d q = p.cwiseAbs() - b_;
    Vector3d g;
    if (q.maxCoeff() > 0) {
      g = q.cwiseMax(0.0).normalized();  // towards p from its closest point on the box
    } else {
      int axis;
      q.maxCoeff(&axis);  // nearest face
      g = Vector3d::Zero();
      g[axis] = 1.0;
    }
    for (int a = 0; a < 3; ++a)
      if (p[a] < 0) g[a] = -g[a];
    return g;
  }

 private:
  Vector3d b_;
};

// A hollow sphere: the set of points whose distance to the centre is within [r0, r1].
class Shell : public AnalyticShape {
 public:
  Shell(double inner, double outer) : mid_(0.5 * (inner + outer)), half_(0.5 * (outer - inner)) {}
  double distance(const Vector3d& p) const override { return std::abs(p.norm() - mid_) - half_; }
  Vector3d gradient(const Vector3d& p) const override {
    const Vector3d radial = normalized_or_fallback(p);
    return p.norm() >= mid_ ? radial : Vector3d(-radial);
  }

 private:
  double mid_, half_;
};

// Union of two spheres. Exact: outside, the distance to a union is the smaller distance; inside,
// the closest boundary point is either a radial projection onto one sphere that lands outside the
// other, or the closest point on the crease circle where the spheres meet.
class TwoSphereUnion : public AnalyticShape {
 public:
  TwoSphereUnion(Vector3d c0, double r0, Vector3d c1, double r1) : c_{c0, c1}, r_{r0, r1} {
    const Vector3d axis = c1 - c0;
    const double d = axis.norm();
    axis_ = axis / d;
    const double t = (d * d + r0 * r0 - r1 * r1) / (2 * d);  // crease plane offset from c0
    crease_centre_ = c0 + t * axis_;
    crease_radius_ = std::sqrt(r0 * r0 - t * t);
  }
  double distance(const Vector3d& p) const override { return closest(p).first; }
  Vector3d gradient(const Vector3d& p) const override {
    const auto [d, q] = closest(p);
    const Vector3d v = p - q;
    if (v.norm() > 0) return d >= 0 ? Vector3d(v.normalized()) : Vector3d(-v.normalized());
    return normalized_or_fallback(p - c_[0]);
  }

 private:
  bool inside_sphere(int s, const Vector3d& p) const { return (p - c_[s]).norm() < r_[s]; }

  // (signed distance, closest boundary point)
  std::pair<double, Vector3d> closest(const Vector3d& p) const {
    const double d[2] = {(p - c_[0]).norm() - r_[0], (p - c_[1]).norm() - r_[1]};
    if (d[0] >= 0 && d[1] >= 0) {  // outside: the nearer sphere's projection
      const int s = d[0] <= d[1] ? 0 : 1;
      return {d[s], c_[s] + r_[s] * normalized_or_fallback(p - c_[s])};
    }
    double best = std::numeric_limits<double>::infinity();
    Vector3d best_point = p;
    for (int s = 0; s < 2; ++s) {
      const Vector3d q = c_[s] + r_[s] * normalized_or_fallback(p - c_[s]);
      if (inside_sphere(1 - s, q)) continue;  // that part of sphere s is not on the boundary
      if (std::abs(d[s]) < best) best = std::abs(d[s]), best_point = q;
    }
    Vector3d radial = p - crease_centre_;
    radial -= radial.dot(axis_) * axis_;
    const Vector3d q =
        crease_centre_ + crease_radius_ * (radial.norm() > 0 ? Vector3d(radial.normalized())
                                                             : axis_.unitOrthogonal());
    if ((p - q).norm() < best) best = (p - q).norm(), best_point = q;
    return {-best, best_point};
  }

  Vector3d c_[2];
  double r_[2];
  Vector3d axis_, crease_centre_;
  double crease_radius_;
};

}  // namespace

std::vector<std::string> builtin_shape_names() {
  return {"sphere", "torus", "box", "plate", "shell", "csg"};
}

std::unique_ptr<AnalyticShape> make_builtin_shape(const std::string& name) {
  if (name == "sphere") return std::make_unique<Sphere>(Vector3d::Zero(), 0.6);
  if (name == "torus") return std::make_unique<Torus>(0.55, 0.25);
  if (name == "box") return std::make_unique<Box>(Vector3d(0.6, 0.45, 0.35));
  if (name == "plate") return std::make_unique<Box>(Vector3d(0.7, 0.5, 0.06));
  if (name == "shell") return std::make_unique<Shell>(0.55, 0.65);
  if (name == "csg")
    return std::make_unique<TwoSphereUnion>(Vector3d(-0.3, -0.05, 0.02), 0.5,
                                            Vector3d(0.35, 0.1, -0.03), 0.42);
  std::string known;
  for (const auto& n : builtin_shape_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown built-in shape '" + name + "' (known: " + known + ")");
}

bool is_builtin_spec(const std::string& text) {
  return text.rfind("builtin:", 0) == 0;
}

BuiltinSpec parse_builtin_spec(const std::string& text) {
  if (!is_builtin_spec(text)) throw Error("'" + text + "' is not a built-in specification");
  const std::string body = text.substr(8);
  const auto at = body.find('@');
  if (at == std::string::npos)
    throw Error("built-in '" + text +
                "' needs a resolution: builtin:NAME@N or builtin:NAME@random:COUNT");
  BuiltinSpec spec;
  spec.name = body.substr(0, at);
  make_builtin_shape(spec.name);  // rejects unknown names
  std::string rest = body.substr(at + 1);
  const bool random = rest.rfind("random:", 0) == 0;
  if (random) rest = rest.substr(7);
  long long value = 0;
  std::size_t used = 0;
  try {
    value = std::stoll(rest, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != rest.size())
    throw Error("built-in '" + text + "': '" + rest + "' is not a whole number");
  spec.random = random;
  // The ranges of sample's --random (at most 1e8: more ended as "out of memory", with advice for
  // the band) and --res.
  if (random) {
    const long long most = (long long)option_range("--random").hi;
    if (value < 4 || value > most)
      throw Error("built-in '" + text + "': the random samples must number 4 to " +
                  std::to_string(most));
    spec.count = std::size_t(value);
  } else {
    const OptionRange& res = option_range("--res");
    if (value < (long long)res.lo || value > (long long)res.hi)
      throw Error("built-in '" + text + "': grid resolution must be between " +
                  std::to_string((long long)res.lo) + " and " + std::to_string((long long)res.hi));
    spec.resolution = int(value);
  }
  return spec;
}

}  // namespace sdfcontour
