// Writes tests/data/rotated_box.vdb: a level set (half width 3 voxels) of the box of half sides
// (0.3, 0.2, 0.12) centred at (0.15, 0.05, 0.25), whose transform scales by 0.05, rotates by 0.5
// about z and 0.3 about x, and moves by (0.1, -0.2, 0.3): the Python tests check that every
// reader puts the surface where the transform says.
//
//   build/tests/make_rotated_box tests/data/rotated_box.vdb
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_rotated_box OUT.vdb\n");
    return 2;
  }
  openvdb::initialize();
  const double voxel = 0.05;
  const openvdb::Vec3d centre(0.15, 0.05, 0.25), half(0.3, 0.2, 0.12);
  auto xform = openvdb::math::Transform::createLinearTransform(voxel);
  xform->preRotate(0.5, openvdb::math::Z_AXIS);
  xform->preRotate(0.3, openvdb::math::X_AXIS);
  xform->postTranslate(openvdb::Vec3d(0.1, -0.2, 0.3));
  auto grid = openvdb::FloatGrid::create(float(3 * voxel));
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  grid->setTransform(xform);
  grid->setName("surface");
  auto accessor = grid->getAccessor();
  for (int i = -24; i <= 24; ++i)
    for (int j = -24; j <= 24; ++j)
      for (int k = -24; k <= 24; ++k) {
        const openvdb::Vec3d p = xform->indexToWorld(openvdb::Coord(i, j, k)) - centre;
        openvdb::Vec3d q(std::abs(p[0]) - half[0], std::abs(p[1]) - half[1],
                         std::abs(p[2]) - half[2]);
        const double outside =
            openvdb::Vec3d(std::max(q[0], 0.0), std::max(q[1], 0.0), std::max(q[2], 0.0)).length();
        const double d = outside + std::min(std::max({q[0], q[1], q[2]}), 0.0);
        if (std::abs(d) < 3 * voxel) accessor.setValue(openvdb::Coord(i, j, k), float(d));
      }
  openvdb::tools::signedFloodFill(grid->tree());
  openvdb::io::File(argv[1]).write({grid});
  return 0;
}
