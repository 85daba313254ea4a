#include "reconstruction/poisson/conjugate_gradients.h"

namespace sdfcontour::poisson {

CgState conjugate_gradients(const OctreeLevel& L, const std::vector<char>& solved, LevelSystem S,
                            std::vector<double>& x, const CgOptions& o) {
  std::vector<double> b = std::move(S.b);
  return conjugate_gradients(
      L.nodes.size(), solved, std::move(b),
      [&](const std::vector<double>& in, std::vector<double>& out) {
        return multiply(L, solved, S, in, out);
      },
      [&](std::size_t v) { return S.diagonal(v); }, x, o);
}

}  // namespace sdfcontour::poisson
