// The band samples of a grid on their lattice, and the search for the spheres (radius |value|)
// that reach a point: what lattice_contact_points.cpp's filter and rescues read.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// Lattice samples per chunk of a column (counted from k = 0) that the sphere search bounds by its
// largest radius.
constexpr int kChunk = 4;

// The spheres that come within `widen` of a box, gathered once for the points that nearby samples
// test: each point then reads this short list, not the lattice, in the lattice's order.
struct SphereList {
  Eigen::Vector3d lo, hi;          // the box
  double widen = 0;                // how far beyond the box the spheres were gathered
  std::vector<double> x, y, z, r;  // per sphere: its centre and radius (|value|)
  std::vector<long> sample;        // per sphere: its band sample

  // Whether the list holds every sphere that comes within `extra` of c.
  bool covers(const Eigen::Vector3d& c, double extra) const {
    const double in = widen - extra;
    return in >= 0 && (c.array() >= lo.array() - in).all() && (c.array() <= hi.array() + in).all();
  }

  // Lattice::any_sphere_near's answer where the list covers c (the same squared distances).
  template <class F>
  bool any_sphere_near(const Eigen::Vector3d& c, double extra, long self, F&& f) const {
    for (std::size_t t = next_near(c, extra, 0); t < r.size(); t = next_near(c, extra, t + 1)) {
      const double dx = x[t] - c[0], dy = y[t] - c[1], dz = z[t] - c[2];
      const double d2 = (dx * dx + dy * dy) + dz * dz, reach = r[t] + extra;
      if (d2 < reach * reach && sample[t] != self && f(sample[t], d2)) return true;
    }
    return false;
  }

  // The first sphere from `t` on that may come within `extra` of c (a superset of those that
  // do), or the list's size. A sample's list holds hundreds of spheres and few reach c: this
  // scan is vectorised where the processor allows (lattice_spheres.cpp).
  std::size_t next_near(const Eigen::Vector3d& c, double extra, std::size_t t) const;
};

// The band samples on their lattice, held compactly: memory in the band, not in the grid (a dense
// index per lattice sample was 0.84 GB of a 1024^3 grid's brick of 512). A grid's band is in C
// order, so each column's samples are consecutive band indices, sorted along the column, in runs
// of consecutive places (one per crossing of the surface, mostly).
class Lattice {
 public:
  // band: a grid's band samples, in the grid's C order (select_band's).
  Lattice(const GridGeometry& grid, const BandSamples& band);

  const Eigen::Vector3d& spacing() const { return h_; }
  const PointMatrix& points() const { return band_.samples.points; }
  const Eigen::VectorXd& values() const { return band_.samples.values; }
  double value(long s) const { return band_.samples.values[Eigen::Index(s)]; }
  Eigen::Vector3d point(long s) const { return band_.samples.points.row(Eigen::Index(s)); }
  std::array<int, 3> index(long s) const {
    const long p = band_.source[std::size_t(s)];
    return {int(p / (long(n_[1]) * n_[2])), int(p / n_[2] % n_[1]), int(p % n_[2])};
  }

  // The band samples at (i, j, k0..k1) into out[0 .. k1 - k0]: -1 where there is none.
  void along(int i, int j, int k0, int k1, long* out) const {
    std::fill(out, out + (k1 - k0 + 1), -1L);
    if (i < 0 || j < 0 || i >= n_[0] || j >= n_[1]) return;
    const std::size_t column = std::size_t(i) * n_[1] + j;
    for (int r = column_runs_[column]; r < column_runs_[column + 1]; ++r) {
      const Run& run = runs_[std::size_t(r)];
      const int last = run.first + runs_[std::size_t(r) + 1].begin - 1 - run.begin;
      for (int k = std::max(k0, run.first); k <= std::min(k1, last); ++k)
        out[k - k0] = run.begin + k - run.first;
    }
  }

  // Calls f(j, squared distance from c to p_j) for each band sample j != self whose sphere holds
  // c (|c - p_j| < |value_j|), until f returns true; returns whether one did.
  template <class F>
  bool any_sphere_holding(const Eigen::Vector3d& c, long self, F&& f) const {
    return any_sphere_near(c, 0.0, self, std::forward<F>(f));
  }

  // Into `out`: every sphere that comes within `widen` of the box [lo, hi] (a superset of those
  // that come within `widen` of a point there), in the lattice's order.
  void gather(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double widen,
              SphereList& out) const;

  // The same for the spheres that come within `extra` of c (|c - p_j| < |value_j| + extra).
  template <class F>
  bool any_sphere_near(const Eigen::Vector3d& c, double extra, long self, F&& f) const {
    auto search = [&](const Run& run, int, int, int ka, int kb, double across) {
      return for_each_chunk_near(run, ka, kb, c[2], c[2], across, extra, [&](int a, int b) {
        for (int k = a; k <= b; ++k) {
          const int t = run.begin + k - run.first;
          const double z = origin_[2] + k * h_[2] - c[2], d2 = across + z * z;
          // First against the radius rounded up to a float, then (rarely) the exact one.
          const double bound = double(radius_up_[std::size_t(t)]) + extra;
          if (!(d2 < bound * bound) || t == self) continue;
          const double exact = std::abs(value(t)) + extra;
          if (d2 < exact * exact && f(long(t), d2)) return true;
        }
        return false;
      });
    };
    return for_each_column_near(c, c, extra, search);
  }

 private:
  // Consecutive places k along a column, held by consecutive band samples.
  struct Run {
    int begin;   // its first band sample (the next run's: one past its last)
    int first;   // its first sample's k
    int chunks;  // where its chunks' maxima start in chunk_max_
  };

  // Calls f(first, last) for each chunk's places of ka..kb along `run` (chunks of kChunk places
  // from k = 0) whose largest sphere, grown by `widen`, can reach the heights [z0, z1] from a
  // column `across` away (squared): a column through a wide band holds far more samples in reach
  // of its largest sphere than spheres that reach. Stops where f returns true, and returns whether
  // it did.
  template <class F>
  bool for_each_chunk_near(const Run& run, int ka, int kb, double z0, double z1, double across,
                           double widen, F&& f) const {
    const float* chunk_max = &chunk_max_[std::size_t(run.chunks - run.first / kChunk)];
    for (int q = ka / kChunk; q * kChunk <= kb; ++q) {
      const int first = std::max(ka, q * kChunk), last = std::min(kb, q * kChunk + kChunk - 1);
      const double below = origin_[2] + first * h_[2], above = origin_[2] + last * h_[2];
      const double gap = below > z1 ? below - z1 : (above < z0 ? z0 - above : 0.0),
                   most = double(chunk_max[q]) + widen;
      if (across + gap * gap < most * most && f(first, last)) return true;
    }
    return false;
  }

  // Calls f(run, i, j, ka, kb, across) for the places ka..kb of each run along column (i, j) whose
  // spheres, grown by `widen`, can reach the box [lo, hi] (by the column's largest): `across`
  // the column's squared distance to the box across x and y. Stops where f returns true, and
  // returns whether it did.
  template <class F>
  bool for_each_column_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double widen,
                            F&& f) const {
    const double far = largest_ + widen;
    const Eigen::Vector3d first = (lo.array() - far - origin_.array()) / h_.array();
    const Eigen::Vector3d last = (hi.array() + far - origin_.array()) / h_.array();
    if (!(first.allFinite() && last.allFinite())) return false;
    // (Beside the box its distance; a point's box gives |x - c| exactly, as x - c would.)
    auto gap = [](double x, double from, double to) {
      return x < from ? from - x : (x > to ? x - to : 0.0);
    };
    const int i0 = std::max(0, int(std::ceil(first[0]))), i1 = std::min(n_[0] - 1, int(last[0]));
    const int j0 = std::max(0, int(std::ceil(first[1]))), j1 = std::min(n_[1] - 1, int(last[1]));
    for (int i = i0; i <= i1; ++i) {
      const double dx = gap(origin_[0] + i * h_[0], lo[0], hi[0]);
      for (int j = j0; j <= j1; ++j) {
        const std::size_t column = std::size_t(i) * n_[1] + j;
        const double dy = gap(origin_[1] + j * h_[1], lo[1], hi[1]);
        const double across = dx * dx + dy * dy, top = double(column_max_[column]) + widen;
        if (across >= top * top) continue;
        const double reach = std::sqrt(top * top - across);
        const int k0 = std::max(0, int(std::ceil((lo[2] - reach - origin_[2]) / h_[2])));
        const int k1 = std::min(n_[2] - 1, int((hi[2] + reach - origin_[2]) / h_[2]));
        for (int r = column_runs_[column]; r < column_runs_[column + 1]; ++r) {
          const Run& run = runs_[std::size_t(r)];
          if (run.first > k1) break;
          const int last_k = run.first + runs_[std::size_t(r) + 1].begin - 1 - run.begin;
          const int ka = std::max(k0, run.first), kb = std::min(k1, last_k);
          if (ka <= kb && f(run, i, j, ka, kb, across)) return true;
        }
      }
    }
    return false;
  }

  const BandSamples& band_;
  std::array<int, 3> n_;
  Eigen::Vector3d origin_, h_;
  std::unique_ptr<float[]> radius_up_;  // per band sample: |value| rounded up to a float
  std::vector<int> column_runs_;        // per column: its first run (and one past the last)
  std::vector<Run> runs_;               // in band order, and one past the last
  std::vector<float> column_max_;       // per column: its largest radius_up
  std::vector<float> chunk_max_;  // per run, per chunk of kChunk it meets: its largest radius_up
  double largest_ = 0;
};

}  // namespace sdfcontour::detail
