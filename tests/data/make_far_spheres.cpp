// Writes tests/data/far_spheres.vdb: one level set (half width 3 voxels, voxel 0.05) of two
// spheres of radius 0.6, one at the origin and one 1e5 voxels away along the diagonal: the
// Python tests check that every reader costs the active voxels, not their box (1e15 voxels).
//
//   build/tests/make_far_spheres tests/data/far_spheres.vdb
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_far_spheres OUT.vdb\n");
    return 2;
  }
  openvdb::initialize();
  const float voxel = 0.05f, radius = 0.6f, far = 1e5f * voxel;
  auto scene = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
      radius, openvdb::Vec3f(0, 0, 0), voxel, 3.f);
  auto other = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
      radius, openvdb::Vec3f(far, far, far), voxel, 3.f);
  openvdb::tools::csgUnion(*scene, *other);
  scene->setName("surface");
  openvdb::io::File(argv[1]).write({scene});
  return 0;
}
