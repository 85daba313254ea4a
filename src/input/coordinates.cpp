#include "sdfcontour/input/coordinates.h"

#include <cmath>

namespace sdfcontour {

void require_coordinates(const PointMatrix& points, const std::string& what) {
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(points(i, a)) <= kLargestCoordinate))
        throw Error(what + " has a NaN, infinite or too large (over 1e30) coordinate (row " +
                    std::to_string(i) + ")");
}

}  // namespace sdfcontour
