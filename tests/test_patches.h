// A flat triangulated patch, which the projection's and the crossing search's tests share.
#pragma once

#include "sdfcontour/types.h"

namespace sdfcontour::test {

/// A flat square of (n x n) vertices `step` apart at height z, centred on the z axis, facing +z.
inline Mesh flat_patch(int n, double step, double z) {
  Mesh m;
  m.vertices.resize(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.vertices.row(j * n + i) << (i - (n - 1) / 2.0) * step, (j - (n - 1) / 2.0) * step, z;
  m.triangles.resize(2 * (n - 1) * (n - 1), 3);
  int t = 0;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i;
      m.triangles.row(t++) << a, a + 1, a + n + 1;
      m.triangles.row(t++) << a, a + n + 1, a + n;
    }
  return m;
}

}  // namespace sdfcontour::test
