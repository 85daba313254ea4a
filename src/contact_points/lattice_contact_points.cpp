#include "sdfcontour/contact_points/lattice_contact_points.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

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
  // Fixed pieces of the band, each with its own kept points (the kept are a fraction of the band:
  // a point and normal per band sample were 0.3 GB of a 1024^3 grid's bricks), joined in order.
  constexpr Eigen::Index kPiece = 16384;
  struct Piece {
    std::vector<int> samples;
    std::vector<std::array<double, 6>> kept;  // point, normal
    int zero_gradient = 0, discarded = 0, rescued = 0;
  };
  std::vector<Piece> pieces(std::size_t((n + kPiece - 1) / kPiece));
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
  tbb::parallel_for(std::size_t(0), pieces.size(), [&](std::size_t q) {
    Piece& piece = pieces[q];
    const Eigen::Index begin = Eigen::Index(q) * kPiece, end = std::min(n, begin + kPiece);
    // First where each sample's gradient puts its point; then, box by box, the spheres that meet
    // the box are gathered once for the points there; the outcomes go back into band order.
    thread_local std::vector<std::pair<std::uint64_t, int>> order;
    thread_local std::vector<Eigen::Vector3d> starts;
    thread_local std::vector<Outcome> outcome;
    thread_local std::vector<std::array<double, 6>> found;
    thread_local detail::SphereList spheres;
    order.clear();
    starts.assign(std::size_t(end - begin), Eigen::Vector3d::Zero());
    outcome.assign(std::size_t(end - begin), Outcome::Skipped);
    found.resize(std::size_t(end - begin));
    for (Eigen::Index i = begin; i < end; ++i) {
      if (!band.core[std::size_t(i)] || (only && !(*only)[std::size_t(i)])) continue;
      SamplePoint sample(lattice, options, long(i));
      if (!sample.prepare()) {
        outcome[std::size_t(i - begin)] = Outcome::ZeroGradient;
        continue;
      }
      starts[std::size_t(i - begin)] = sample.start();
      order.emplace_back(box_key(sample.start()), int(i - begin));
    }
    std::sort(order.begin(), order.end());
    for (std::size_t a = 0; a < order.size();) {
      std::size_t b = a;
      Eigen::Vector3d lo = starts[std::size_t(order[a].second)], hi = lo;
      for (; b < order.size() && order[b].first == order[a].first; ++b) {
        lo = lo.cwiseMin(starts[std::size_t(order[b].second)]);
        hi = hi.cwiseMax(starts[std::size_t(order[b].second)]);
      }
      const bool gathered = b - a > 1 && lo.allFinite() && hi.allFinite();
      if (gathered) lattice.gather(lo, hi, near_start_reach(grid.spacing()), spheres);
      for (; a < b; ++a) {
        const int at = order[a].second;
        SamplePoint sample(lattice, options, long(begin + at));
        sample.prepare();
        const Outcome out = sample.solve(gathered ? &spheres : nullptr);
        outcome[std::size_t(at)] = out;
        const Eigen::Vector3d& c = sample.point;
        const Eigen::Vector3d& m = sample.normal;
        if (out == Outcome::Kept || out == Outcome::Rescued)
          found[std::size_t(at)] = {c[0], c[1], c[2], m[0], m[1], m[2]};
      }
    }
    for (Eigen::Index i = begin; i < end; ++i) {
      const Outcome out = outcome[std::size_t(i - begin)];
      piece.zero_gradient += out == Outcome::ZeroGradient;
      piece.discarded += out == Outcome::Discarded;
      piece.rescued += out == Outcome::Rescued;
      if (out == Outcome::Kept || out == Outcome::Rescued) {
        piece.samples.push_back(int(i));
        piece.kept.push_back(found[std::size_t(i - begin)]);
      }
    }
  });
  ContactPoints result;
  std::size_t kept = 0;
  for (const Piece& piece : pieces) kept += piece.samples.size();
  result.samples.reserve(kept);
  result.points.resize(Eigen::Index(kept), 3);
  result.normals.resize(Eigen::Index(kept), 3);
  for (Piece& piece : pieces) {
    result.zero_gradient += piece.zero_gradient;
    result.discarded += piece.discarded;
    result.rescued += piece.rescued;
    for (std::size_t a = 0; a < piece.samples.size(); ++a) {
      const Eigen::Index row = Eigen::Index(result.samples.size());
      result.samples.push_back(piece.samples[a]);
      const auto& x = piece.kept[a];
      result.points.row(row) << x[0], x[1], x[2];
      result.normals.row(row) << x[3], x[4], x[5];
    }
    piece = Piece();
  }
  return result;
}

}  // namespace sdfcontour
