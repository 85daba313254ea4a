#include "sdfcontour/contact_points/lattice_contact_points.h"

#include <tbb/blocked_range.h>
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
#include "pipeline/uninitialised_allocator.h"

namespace sdfcontour {
namespace {

using detail::Lattice;
using detail::lattice_points::kListBox;
using detail::lattice_points::near_start_reach;
using detail::lattice_points::Outcome;
using detail::lattice_points::SamplePoint;

// Each kept sample's row in `result` (-1 where none), in band order, with the outcomes' counts:
// counted per piece of `piece` samples, then numbered, both in parallel.
detail::Unwritten<int> number_kept(const detail::Unwritten<Outcome>& outcome, std::size_t piece,
                                   ContactPoints& result) {
  const std::size_t n = outcome.size(), pieces = (n + piece - 1) / piece;
  auto kept = [&](std::size_t i) {
    return outcome[i] == Outcome::Kept || outcome[i] == Outcome::Rescued;
  };
  std::vector<std::array<long, 4>> counts(pieces + 1, {0, 0, 0, 0});
  tbb::parallel_for(std::size_t(0), pieces, [&](std::size_t q) {
    std::array<long, 4>& c = counts[q + 1];
    for (std::size_t i = q * piece; i < std::min(n, (q + 1) * piece); ++i) {
      c[0] += kept(i);
      c[1] += outcome[i] == Outcome::ZeroGradient;
      c[2] += outcome[i] == Outcome::Discarded;
      c[3] += outcome[i] == Outcome::Rescued;
    }
  });
  for (std::size_t q = 0; q < pieces; ++q)
    for (std::size_t k = 0; k < 4; ++k) counts[q + 1][k] += counts[q][k];
  result.zero_gradient = int(counts.back()[1]);
  result.discarded = int(counts.back()[2]);
  result.rescued = int(counts.back()[3]);
  result.samples.resize(std::size_t(counts.back()[0]));
  detail::Unwritten<int> row(n);
  tbb::parallel_for(std::size_t(0), pieces, [&](std::size_t q) {
    long next = counts[q][0];
    for (std::size_t i = q * piece; i < std::min(n, (q + 1) * piece); ++i) {
      row[i] = kept(i) ? int(next) : -1;
      if (kept(i)) result.samples[std::size_t(next++)] = int(i);
    }
  });
  return row;
}

}  // namespace

int lattice_contact_reach(double largest_in_spacings, const ContactPointOptions& options) {
  // The candidate lies |value| <= largest from its sample, a slid point |value| farther; a sphere
  // holding either has its centre within `largest` of it.
  const double spheres = (options.sphere_slide_rounds > 0 ? 3 : 2) * largest_in_spacings;
  return int(std::ceil(spheres)) + 3;
}

int lattice_contact_reach(const GridGeometry& grid, double largest,
                          const ContactPointOptions& options) {
  return lattice_contact_reach(largest / grid.spacing().minCoeff(), options);
}

ContactPoints lattice_contact_points(const GridGeometry& grid, const BandSamples& band,
                                     const ContactPointOptions& options,
                                     const std::vector<char>* only) {
  if (!(options.tie_tolerance >= 0) || options.sphere_slide_rounds < 0 ||
      !(options.rescue_reach >= 0))
    throw Error(
        "contact points need a tie tolerance >= 0, slide rounds >= 0 and a rescue reach >= 0");
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
  // First where each sample's gradient puts its point, as its box; then the whole band, sorted by
  // box, gathers the spheres that meet each box once for all the points there.
  constexpr Eigen::Index kPiece = 16384;
  const std::size_t pieces_count = std::size_t((n + kPiece - 1) / kPiece);
  detail::Unwritten<Outcome> outcome(static_cast<std::size_t>(n));
  // (A struct, not a std::pair, whose constructor would zero the list on one thread.)
  struct BoxSample {
    std::uint64_t box;
    int sample;
    bool operator<(const BoxSample& o) const {
      return box < o.box || (box == o.box && sample < o.sample);
    }
  };
  detail::Unwritten<BoxSample> order;
  // Each prepared sample's gradient, for the second pass (made again, they were 2-3% of a 512^3
  // run).
  detail::Unwritten<Eigen::Vector3d> gradients(static_cast<std::size_t>(n));
  {
    std::vector<std::vector<BoxSample>> pieces(pieces_count);
    tbb::parallel_for(std::size_t(0), pieces.size(), [&](std::size_t q) {
      const Eigen::Index begin = Eigen::Index(q) * kPiece, end = std::min(n, begin + kPiece);
      for (Eigen::Index i = begin; i < end; ++i) {
        outcome[std::size_t(i)] = Outcome::Skipped;
        if (!band.core[std::size_t(i)] || (only && !(*only)[std::size_t(i)])) continue;
        SamplePoint sample(lattice, options, long(i));
        if (sample.prepare()) {
          pieces[q].push_back({box_key(sample.start()), int(i)});
          gradients[std::size_t(i)] = sample.gradient();
        } else
          outcome[std::size_t(i)] = Outcome::ZeroGradient;
      }
    });
    std::vector<std::size_t> at(pieces.size() + 1, 0);
    for (std::size_t q = 0; q < pieces.size(); ++q) at[q + 1] = at[q] + pieces[q].size();
    order.resize(at.back());
    tbb::parallel_for(std::size_t(0), pieces.size(), [&](std::size_t q) {
      std::copy(pieces[q].begin(), pieces[q].end(), order.begin() + std::ptrdiff_t(at[q]));
      pieces[q] = {};
    });
  }
  tbb::parallel_sort(order.begin(), order.end());
  std::vector<std::size_t> boxes;  // where each box's samples start in `order`, then the end
  for (std::size_t a = 0; a < order.size(); ++a)
    if (a == 0 || order[a].box != order[a - 1].box) boxes.push_back(a);
  boxes.push_back(order.size());
  // Runs of whole boxes of about kPiece samples, each with its kept points and their samples
  // (a point and normal per band sample were 0.3 GB of a 1024^3 grid's bricks), joined in band
  // order below.
  std::vector<std::size_t> runs{0};  // where each run's boxes start in `boxes`, then the end
  for (std::size_t box = 1; box + 1 < boxes.size(); ++box)
    if (boxes[box] - boxes[runs.back()] >= std::size_t(kPiece)) runs.push_back(box);
  runs.push_back(boxes.size() - 1);
  using Found = std::pair<int, std::array<double, 6>>;
  std::vector<std::vector<Found>> found(runs.size() - 1);
  tbb::parallel_for(std::size_t(0), runs.size() - 1, [&](std::size_t run) {
    std::vector<Found>& mine = found[run];
    mine.reserve(boxes[runs[run + 1]] - boxes[runs[run]]);
    thread_local std::vector<SamplePoint> samples;
    thread_local detail::SphereList spheres;
    for (std::size_t box = runs[run]; box < runs[run + 1]; ++box) {
      samples.clear();
      for (std::size_t a = boxes[box]; a < boxes[box + 1]; ++a) {
        samples.emplace_back(lattice, options, long(order[a].sample));
        samples.back().prepare(gradients[std::size_t(order[a].sample)]);
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
  gradients = {};
  ContactPoints result;
  const detail::Unwritten<int> row = number_kept(outcome, std::size_t(kPiece), result);
  result.points.resize(Eigen::Index(result.samples.size()), 3);
  result.normals.resize(Eigen::Index(result.samples.size()), 3);
  tbb::parallel_for(std::size_t(0), found.size(), [&](std::size_t run) {
    for (const Found& f : found[run]) {
      const Eigen::Index r = row[std::size_t(f.first)];
      result.points.row(r) << f.second[0], f.second[1], f.second[2];
      result.normals.row(r) << f.second[3], f.second[4], f.second[5];
    }
    found[run] = {};
  });
  return result;
}

}  // namespace sdfcontour
