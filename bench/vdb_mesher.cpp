// The OpenVDB peer for adaptivity (bench/adaptivity.py): OpenVDB's own mesher
// (tools::volumeToMesh) with its adaptivity, on a grid .npy over [-1, 1]^3, its narrow band of 3
// voxels made a level set. Quads are split in two triangles.
//
//   vdb_mesher GRID.npy OUT.ply ADAPTIVITY
#include <openvdb/openvdb.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <vector>

#include "sdfcontour/io/io.h"
#include "sdfcontour/io/npy.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: vdb_mesher GRID.npy OUT.ply ADAPTIVITY\n";
    return 2;
  }
  try {
    openvdb::initialize();
    const sdfcontour::NpyArray a = sdfcontour::read_npy(argv[1]);
    if (a.shape.size() != 3) throw sdfcontour::Error("the grid must be 3D");
    const int n[3] = {int(a.shape[0]), int(a.shape[1]), int(a.shape[2])};
    const double h = 2.0 / (std::max({n[0], n[1], n[2]}) - 1);
    const float band = float(3 * h);
    auto grid = openvdb::FloatGrid::create(band);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    auto transform = openvdb::math::Transform::createLinearTransform(h);
    transform->postTranslate(openvdb::Vec3d(-1, -1, -1));
    grid->setTransform(transform);
    auto access = grid->getAccessor();
    std::size_t p = 0;
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k, ++p) {
          const float v = float(a.data[p]);
          if (std::abs(v) < band)
            access.setValue(openvdb::Coord(i, j, k), v);
          else if (v < 0)
            access.setValueOff(openvdb::Coord(i, j, k), -band);
        }
    openvdb::tools::signedFloodFill(grid->tree());
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, std::atof(argv[3]));
    sdfcontour::Mesh mesh;
    mesh.vertices.resize(Eigen::Index(points.size()), 3);
    for (std::size_t v = 0; v < points.size(); ++v)
      for (int c = 0; c < 3; ++c) mesh.vertices(Eigen::Index(v), c) = points[v][c];
    mesh.triangles.resize(Eigen::Index(triangles.size() + 2 * quads.size()), 3);
    Eigen::Index t = 0;
    // OpenVDB winds its polygons inward for a level set: reversed, outward.
    for (const auto& tri : triangles)
      mesh.triangles.row(t++) << int(tri[2]), int(tri[1]), int(tri[0]);
    for (const auto& q : quads) {
      mesh.triangles.row(t++) << int(q[2]), int(q[1]), int(q[0]);
      mesh.triangles.row(t++) << int(q[3]), int(q[2]), int(q[0]);
    }
    sdfcontour::write_mesh(argv[2], mesh);
    std::cout << mesh.triangles.rows() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "vdb_mesher: " << e.what() << "\n";
    return 1;
  }
}
