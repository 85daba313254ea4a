#include "sdfcontour/contact_points/gradients.h"

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <cmath>

#include "pipeline/enum_names.h"

namespace sdfcontour {

namespace {
const detail::NameTable<GradientWeighting> kWeightings = {{"uniform", GradientWeighting::Uniform},
                                                          {"volume", GradientWeighting::Volume},
                                                          {"james", GradientWeighting::James}};
}  // namespace

GradientWeighting parse_gradient_weighting(const std::string& name) {
  return detail::parse_name(kWeightings, "gradient weighting", name);
}
std::string gradient_weighting_name(GradientWeighting weighting) {
  return detail::name_of(kWeightings, weighting);
}

namespace {

// Tets whose volume is below this fraction of (longest edge)^3 are too flat for a gradient.
constexpr double kFlatTetRatio = 1e-12;

Eigen::Vector3d row(const PointMatrix& m, Eigen::Index i) {
  return m.row(i).transpose();
}

}  // namespace

PointMatrix tet_gradients(const PointMatrix& points, const Eigen::VectorXd& values,
                          const TetMatrix& tets, std::vector<char>* degenerate,
                          const std::vector<char>* wanted) {
  const Eigen::Index m = tets.rows();
  PointMatrix g(m, 3);
  if (degenerate) degenerate->assign(std::size_t(m), 0);
  tbb::parallel_for(Eigen::Index(0), m, [&](Eigen::Index t) {
    if (wanted && !(*wanted)[std::size_t(t)]) {
      g.row(t).setZero();
      return;
    }
    const Eigen::Vector3d p0 = row(points, tets(t, 0));
    Eigen::Matrix3d E;
    Eigen::Vector3d dv;
    double longest = 0;
    for (int k = 1; k < 4; ++k) {
      E.row(k - 1) = (row(points, tets(t, k)) - p0).transpose();
      dv[k - 1] = values[tets(t, k)] - values[tets(t, 0)];
      longest = std::max(longest, E.row(k - 1).norm());
    }
    const double det = E.determinant();
    if (!(std::abs(det) > kFlatTetRatio * longest * longest * longest)) {
      g.row(t).setZero();
      if (degenerate) (*degenerate)[std::size_t(t)] = 1;
      return;
    }
    // E g = dv: the interpolant's value differences along the three edges from vertex 0.
    g.row(t) = E.partialPivLu().solve(dv).transpose();
  });
  return g;
}

Eigen::VectorXd tet_volumes(const PointMatrix& points, const TetMatrix& tets) {
  Eigen::VectorXd v(tets.rows());
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const Eigen::Vector3d p0 = row(points, tets(t, 0));
    const Eigen::Vector3d a = row(points, tets(t, 1)) - p0, b = row(points, tets(t, 2)) - p0,
                          c = row(points, tets(t, 3)) - p0;
    v[t] = a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

namespace {

// James et al.'s weights of the centroids centroid(0..k-1) around p, written to w[0..k):
// w_t = (1 + lambda . u_t) / |c_t - p|, u_t the unit vector to centroid t and lambda the solution
// of (epsilon I + sum u u^T) lambda = -sum u. `unit` and `length` are scratch of size k.
template <class Centroid>
void james_weights_into(const Eigen::Vector3d& p, Eigen::Index k, const Centroid& centroid,
                        double epsilon, double* w, Eigen::Vector3d* unit, double* length) {
  Eigen::Matrix3d A = epsilon * Eigen::Matrix3d::Identity();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (Eigen::Index t = 0; t < k; ++t) {
    const Eigen::Vector3d r = centroid(t) - p;
    length[t] = r.norm();
    unit[t] = r / length[t];
    A += unit[t] * unit[t].transpose();
    b -= unit[t];
  }
  const Eigen::Vector3d lambda = A.ldlt().solve(b);
  for (Eigen::Index t = 0; t < k; ++t) w[t] = (1.0 + lambda.dot(unit[t])) / length[t];
}

// Per-thread scratch for one star, reused from sample to sample.
struct StarScratch {
  std::vector<int> tets;
  std::vector<double> weights, lengths;
  std::vector<Eigen::Vector3d> units;
  void resize(std::size_t k) {
    weights.resize(k);
    lengths.resize(k);
    units.resize(k);
  }
};

}  // namespace

Eigen::VectorXd james_weights(const Eigen::Vector3d& p, const PointMatrix& centroids,
                              double epsilon) {
  const Eigen::Index k = centroids.rows();
  Eigen::VectorXd w(k), length(k);
  std::vector<Eigen::Vector3d> unit(static_cast<std::size_t>(k));
  james_weights_into(
      p, k, [&](Eigen::Index t) { return row(centroids, t); }, epsilon, w.data(), unit.data(),
      length.data());
  return w;
}

PointMatrix vertex_gradients(const PointMatrix& points, const Eigen::VectorXd& values,
                             const Triangulation& tri, const GradientOptions& options,
                             const std::vector<char>* only) {
  const Eigen::Index n = points.rows();
  std::vector<char> degenerate, wanted;
  if (only) {  // only the stars of the samples asked for
    wanted.assign(std::size_t(tri.tets.rows()), 0);
    for (Eigen::Index i = 0; i < n; ++i)
      if ((*only)[std::size_t(i)])
        for (int o = tri.incident_offsets[std::size_t(i)];
             o < tri.incident_offsets[std::size_t(i) + 1]; ++o)
          wanted[std::size_t(tri.incident_tets[std::size_t(o)])] = 1;
  }
  const PointMatrix tet_g =
      tet_gradients(points, values, tri.tets, &degenerate, only ? &wanted : nullptr);
  PointMatrix g = PointMatrix::Zero(n, 3);
  tbb::enumerable_thread_specific<StarScratch> scratch;
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    if (only && !(*only)[std::size_t(i)]) return;
    StarScratch& star = scratch.local();
    std::vector<int>& ts = star.tets;
    ts.clear();
    for (int o = tri.incident_offsets[std::size_t(i)]; o < tri.incident_offsets[std::size_t(i) + 1];
         ++o)
      if (!degenerate[std::size_t(tri.incident_tets[std::size_t(o)])])
        ts.push_back(tri.incident_tets[std::size_t(o)]);
    if (ts.empty()) return;
    star.resize(ts.size());
    const Eigen::Index k = Eigen::Index(ts.size());
    Eigen::Map<Eigen::VectorXd> w(star.weights.data(), k);
    if (options.weighting == GradientWeighting::Uniform) {
      w.setOnes();
    } else if (options.weighting == GradientWeighting::Volume) {
      for (std::size_t a = 0; a < ts.size(); ++a) {
        const int t = ts[a];
        const Eigen::Vector3d p0 = row(points, tri.tets(t, 0));
        w[Eigen::Index(a)] = std::abs((row(points, tri.tets(t, 1)) - p0)
                                          .dot((row(points, tri.tets(t, 2)) - p0)
                                                   .cross(row(points, tri.tets(t, 3)) - p0))) /
                             6.0;
      }
    } else {
      auto centroid = [&](Eigen::Index a) {
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (int v = 0; v < 4; ++v) c += row(points, tri.tets(ts[std::size_t(a)], v));
        return Eigen::Vector3d(c / 4.0);
      };
      james_weights_into(row(points, i), k, centroid, options.james_epsilon, w.data(),
                         star.units.data(), star.lengths.data());
    }
    const double total = w.sum();
    // James weights may cancel; an average with no net weight falls back to uniform weights.
    if (!(std::abs(total) > 1e-12 * w.cwiseAbs().sum())) w.setOnes();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::size_t a = 0; a < ts.size(); ++a) sum += w[Eigen::Index(a)] * row(tet_g, ts[a]);
    g.row(i) = (sum / w.sum()).transpose();
  });
  return g;
}

PointMatrix knn_gradients(const PointMatrix& points, const Eigen::VectorXd& values, int k) {
  if (k < 3) throw Error("k-nearest-neighbour gradients need k >= 3, got " + std::to_string(k));
  using K = CGAL::Simple_cartesian<double>;
  using Point = K::Point_3;
  const Eigen::Index n = points.rows();
  std::vector<Point> pts(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    pts[std::size_t(i)] = Point(points(i, 0), points(i, 1), points(i, 2));
  using Map = CGAL::Pointer_property_map<Point>::type;
  using Traits = CGAL::Search_traits_adapter<std::size_t, Map, CGAL::Search_traits_3<K>>;
  using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
  using Tree = Search::Tree;
  Map map = CGAL::make_property_map(pts);
  std::vector<std::size_t> ids(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = i;
  Tree tree(ids.begin(), ids.end(), Tree::Splitter(), Traits(map));
  tree.build();
  PointMatrix g = PointMatrix::Zero(n, 3);
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    Search search(tree, pts[std::size_t(i)], unsigned(k + 1), 0, true, Search::Distance(map));
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int used = 0;
    for (const auto& hit : search) {
      const Eigen::Index j = Eigen::Index(hit.first);
      if (j == i || used == k) continue;
      const Eigen::Vector3d d = row(points, j) - row(points, i);
      A += d * d.transpose();
      b += d * (values[j] - values[i]);
      ++used;
    }
    // Least squares for g in: values_i + g.(p_j - p_i) ~ values_j.
    Eigen::ColPivHouseholderQR<Eigen::Matrix3d> qr(A);
    if (qr.rank() == 3) g.row(i) = qr.solve(b).transpose();
  });
  return g;
}

}  // namespace sdfcontour
