#include "sdfcontour/contact_points/lattice_contact_points.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "contact_points/lattice_sample_point.h"
#include "contact_points/lattice_spheres.h"

namespace sdfcontour {
namespace {

using detail::Lattice;
using detail::lattice_points::kListBox;
using detail::lattice_points::near_start_reach;
using detail::lattice_points::Outcome;
using detail::lattice_points::SamplePoint;

}  // namespace

int lattice_contact_reach(const GridGeometry& grid, double largest,
                          const ContactPointOptions& options) {
  // The candidate lies |value| <= largest from its sample, a slid point |value| farther; a sphere
  // holding either has its centre within `largest` of it.
  const double spheres = (options.sphere_slide_rounds > 0 ? 3 : 2) * largest;
  return int(std::ceil(spheres / grid.spacing().minCoeff())) + 2;
}

ContactPoints lattice_contact_points(const GridGeometry& grid, const BandSamples& band,
                                     const ContactPointOptions& options,
                                     const std::vector<char>* only) {
  if (!(options.tie_tolerance >= 0) || options.sphere_slide_rounds < 0)
    throw Error("contact points need a tie tolerance >= 0 and slide rounds >= 0");
  const Eigen::Index n = band.samples.values.size();
  const Lattice lattice(grid, band);
  const double h = grid.spacing().maxCoeff();
  const Eigen::Vector3d origin = grid.point(0, 0, 0);
  // The box (kListBox spacings a side) where a sample's point lies, as one key.
  auto box_key = [&](const Eigen::Vector3d& c) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double at = std::floor((c[a] - origin[a]) / (kListBox * h));
      key = key << 21 |
            std::uint64_t(std::isnan(at) ? 0.0 : std::clamp(at, -1048576.0, 1048575.0) + 1048576.0);
    }
    return key;
  };
  // First where each sample's gradient puts its point, as its box; then, box by box over the
  // whole band, the spheres that meet the box are gathered once for the points there (pieces of
  // the band in its own order gathered a box once per piece that reached it).
  std::vector<Outcome> outcome(std::size_t(n), Outcome::Skipped);
  std::vector<std::pair<std::uint64_t, int>> order;
  {
    constexpr Eigen::Index kPiece = 16384;
    std::vector<std::vector<std::pair<std::uint64_t, int>>> pieces(
        std::size_t((n + kPiece - 1) / kPiece));
    tbb::parallel_for(std::size_t(0), pieces.size(), [&](std::size_t q) {
      const Eigen::Index begin = Eigen::Index(q) * kPiece, end = std::min(n, begin + kPiece);
      for (Eigen::Index i = begin; i < end; ++i) {
        if (!band.core[std::size_t(i)] || (only && !(*only)[std::size_t(i)])) continue;
        SamplePoint sample(lattice, options, long(i));
        if (sample.prepare())
          pieces[q].emplace_back(box_key(sample.start()), int(i));
        else
          outcome[std::size_t(i)] = Outcome::ZeroGradient;
      }
    });
    std::size_t total = 0;
    for (const auto& piece : pieces) total += piece.size();
    order.reserve(total);
    for (auto& piece : pieces) {
      order.insert(order.end(), piece.begin(), piece.end());
      piece = {};
    }
  }
  tbb::parallel_sort(order.begin(), order.end());
  std::vector<std::size_t> boxes;  // where each box's samples start in `order`, then the end
  for (std::size_t a = 0; a < order.size(); ++a)
    if (a == 0 || order[a].first != order[a - 1].first) boxes.push_back(a);
  boxes.push_back(order.size());
  // Each box's kept points with their samples, joined in band order below (a point and normal
  // per band sample were 0.3 GB of a 1024^3 grid's bricks).
  using Found = std::pair<int, std::array<double, 6>>;
  tbb::enumerable_thread_specific<std::vector<Found>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, boxes.size() - 1), [&](const auto& range) {
    std::vector<Found>& mine = found.local();
    thread_local std::vector<SamplePoint> samples;
    thread_local detail::SphereList spheres;
    for (std::size_t box = range.begin(); box < range.end(); ++box) {
      samples.clear();
      for (std::size_t a = boxes[box]; a < boxes[box + 1]; ++a) {
        samples.emplace_back(lattice, options, long(order[a].second));
        samples.back().prepare();
      }
      Eigen::Vector3d lo = samples.front().start(), hi = lo;
      for (const SamplePoint& sample : samples) {
        lo = lo.cwiseMin(sample.start());
        hi = hi.cwiseMax(sample.start());
      }
      const bool gathered = samples.size() > 1 && lo.allFinite() && hi.allFinite();
      if (gathered) lattice.gather(lo, hi, near_start_reach(grid.spacing()), spheres);
      for (SamplePoint& sample : samples) {
        const Outcome out = sample.solve(gathered ? &spheres : nullptr);
        outcome[std::size_t(sample.sample())] = out;
        const Eigen::Vector3d& c = sample.point;
        const Eigen::Vector3d& m = sample.normal;
        if (out == Outcome::Kept || out == Outcome::Rescued)
          mine.push_back({int(sample.sample()), {c[0], c[1], c[2], m[0], m[1], m[2]}});
      }
    }
  });
  order = {};
  ContactPoints result;
  std::vector<int> row(std::size_t(n), -1);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Outcome out = outcome[std::size_t(i)];
    result.zero_gradient += out == Outcome::ZeroGradient;
    result.discarded += out == Outcome::Discarded;
    result.rescued += out == Outcome::Rescued;
    if (out == Outcome::Kept || out == Outcome::Rescued) {
      row[std::size_t(i)] = int(result.samples.size());
      result.samples.push_back(int(i));
    }
  }
  result.points.resize(Eigen::Index(result.samples.size()), 3);
  result.normals.resize(Eigen::Index(result.samples.size()), 3);
  for (std::vector<Found>& mine : found) {
    tbb::parallel_for(std::size_t(0), mine.size(), [&](std::size_t a) {
      const Eigen::Index r = row[std::size_t(mine[a].first)];
      const auto& x = mine[a].second;
      result.points.row(r) << x[0], x[1], x[2];
      result.normals.row(r) << x[3], x[4], x[5];
    });
    mine = {};
  }
  return result;
}

}  // namespace sdfcontour
