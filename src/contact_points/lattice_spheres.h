// The band samples of a grid on their lattice, and the search for the spheres (radius |value|)
// that reach a point: what lattice_contact_points.cpp's filter and rescues read.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/types.h"

namespace sdfcontour::detail {

// Lattice samples per chunk of a column that the sphere search bounds by its largest radius.
constexpr int kChunk = 4;

// The band samples on their lattice: each lattice sample's band index (or -1), and the largest
// radius |value| of the band samples in each column and in each chunk of kChunk along a column.
class Lattice {
 public:
  // Built in parallel, every large array written first there: a brick's slots and chunk maxima
  // are 64 MB and 34 MB of fresh pages at 256^3, whose faults took a tenth of the fast path's
  // time when they were serial.
  Lattice(const GridGeometry& grid, const BandSamples& band)
      : band_(band),
        n_(grid.dims),
        chunks_((n_[2] + kChunk - 1) / kChunk),
        origin_(grid.point(0, 0, 0)),
        h_(grid.spacing()),
        slot_(new int[grid.size()]),
        radius_(new double[band.source.size()]),
        column_max_(std::size_t(n_[0]) * n_[1], 0.0),
        chunk_max_(new double[column_max_.size() * std::size_t(chunks_)]) {
    const std::size_t samples = band.source.size(), columns = column_max_.size();
    if (samples > std::size_t(std::numeric_limits<int>::max()))
      throw Error("too many band samples in one brick: use smaller bricks (--brick-size)");
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.size(), 1 << 16), [&](auto r) {
      std::fill(slot_.get() + r.begin(), slot_.get() + r.end(), -1);
    });
    tbb::parallel_for(std::size_t(0), samples, [&](std::size_t s) {
      slot_[std::size_t(band.source[s])] = int(s);
      radius_[s] = std::abs(band.samples.values[Eigen::Index(s)]);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, columns, 256), [&](auto r) {
      for (std::size_t column = r.begin(); column < r.end(); ++column) {
        const int* slot = &slot_[column * std::size_t(n_[2])];
        double* in_chunks = &chunk_max_[column * std::size_t(chunks_)];
        std::fill(in_chunks, in_chunks + chunks_, 0.0);
        for (int k = 0; k < n_[2]; ++k)
          if (slot[k] >= 0) {
            const double radius = radius_[std::size_t(slot[k])];
            column_max_[column] = std::max(column_max_[column], radius);
            in_chunks[k / kChunk] = std::max(in_chunks[k / kChunk], radius);
          }
      }
    });
    largest_ = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, columns), 0.0,
        [&](auto r, double m) {
          for (std::size_t c = r.begin(); c < r.end(); ++c) m = std::max(m, column_max_[c]);
          return m;
        },
        [](double a, double b) { return std::max(a, b); });
  }

  const Eigen::Vector3d& spacing() const { return h_; }
  double value(long s) const { return band_.samples.values[Eigen::Index(s)]; }
  Eigen::Vector3d point(long s) const { return band_.samples.points.row(Eigen::Index(s)); }
  std::array<int, 3> index(long s) const {
    const long p = band_.source[std::size_t(s)];
    return {int(p / (long(n_[1]) * n_[2])), int(p / n_[2] % n_[1]), int(p % n_[2])};
  }

  // The band sample at lattice (i, j, k), or -1.
  long find(int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i >= n_[0] || j >= n_[1] || k >= n_[2]) return -1;
    return slot_[(std::size_t(i) * n_[1] + j) * n_[2] + k];
  }

  // Calls f(j, squared distance from c to p_j) for each band sample j != self whose sphere holds
  // c (|c - p_j| < |value_j|), until f returns true; returns whether one did.
  template <class F>
  bool any_sphere_holding(const Eigen::Vector3d& c, long self, F&& f) const {
    return any_sphere_near(c, 0.0, self, std::forward<F>(f));
  }

  // The same for the spheres that come within `extra` of c (|c - p_j| < |value_j| + extra).
  template <class F>
  bool any_sphere_near(const Eigen::Vector3d& c, double extra, long self, F&& f) const {
    const double far = largest_ + extra;
    const Eigen::Vector3d lo = (c.array() - far - origin_.array()) / h_.array();
    const Eigen::Vector3d hi = (c.array() + far - origin_.array()) / h_.array();
    if (!(lo.allFinite() && hi.allFinite())) return false;
    const int i0 = std::max(0, int(std::ceil(lo[0]))), i1 = std::min(n_[0] - 1, int(hi[0]));
    const int j0 = std::max(0, int(std::ceil(lo[1]))), j1 = std::min(n_[1] - 1, int(hi[1]));
    for (int i = i0; i <= i1; ++i) {
      const double dx = origin_[0] + i * h_[0] - c[0];
      for (int j = j0; j <= j1; ++j) {
        const std::size_t column = std::size_t(i) * n_[1] + j;
        const double dy = origin_[1] + j * h_[1] - c[1];
        const double across = dx * dx + dy * dy, top = column_max_[column] + extra;
        if (across >= top * top) continue;
        const double reach = std::sqrt(top * top - across);
        const int k0 = std::max(0, int(std::ceil((c[2] - reach - origin_[2]) / h_[2])));
        const int k1 = std::min(n_[2] - 1, int((c[2] + reach - origin_[2]) / h_[2]));
        const double* chunk_max = &chunk_max_[column * std::size_t(chunks_)];
        const int* slot = &slot_[column * std::size_t(n_[2])];
        // Chunk by chunk, each skipped where its largest sphere cannot reach c.
        for (int q = k0 / kChunk; q * kChunk <= k1; ++q) {
          const int a = std::max(k0, q * kChunk), b = std::min(k1, q * kChunk + kChunk - 1);
          const double below = origin_[2] + a * h_[2] - c[2], above = origin_[2] + b * h_[2] - c[2];
          const double dz = below > 0 ? below : (above < 0 ? -above : 0.0),
                       m = chunk_max[q] + extra;
          if (across + dz * dz >= m * m) continue;
          for (int k = a; k <= b; ++k) {
            const int t = slot[k];
            if (t < 0 || t == self) continue;
            const double z = origin_[2] + k * h_[2] - c[2];
            const double d2 = across + z * z, r = radius_[std::size_t(t)] + extra;
            if (d2 < r * r && f(long(t), d2)) return true;
          }
        }
      }
    }
    return false;
  }

 private:
  const BandSamples& band_;
  std::array<int, 3> n_;
  int chunks_;  // per column
  Eigen::Vector3d origin_, h_;
  std::unique_ptr<int[]> slot_;       // per lattice sample: its band index, or -1
  std::unique_ptr<double[]> radius_;  // per band sample
  std::vector<double> column_max_;
  std::unique_ptr<double[]> chunk_max_;  // per column, kChunk samples at a time
  double largest_ = 0;
};

}  // namespace sdfcontour::detail
