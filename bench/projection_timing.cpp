// The projection onto the contact points' local fits alone, timed: one stage that a whole run's
// wall time hides in this machine's drift. A mesh (GCP's own, or marching cubes') is projected
// onto a run's contact points (`sdfcontour contour GRID -o MESH --points POINTS`), `repeats`
// times, each from the same mesh, on all cores. Prints the fastest and the median seconds, the
// vertices moved and a checksum of the projected vertices: two builds with the same checksum made
// the same mesh, to the last bit.
//
// Usage: projection_timing MESH.ply POINTS.ply SPACING [REPEATS] [--fans]
//   SPACING: the grid's spacing; --fans: the edge fans' options (one robust round, not two).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "sdfcontour/io/io.h"
#include "sdfcontour/reconstruction/contact_projection.h"

using namespace sdfcontour;

namespace {

// FNV-1a over the vertices' bytes.
std::uint64_t checksum(const Mesh& mesh) {
  std::uint64_t h = 1469598103934665603ull;
  const auto* bytes = reinterpret_cast<const unsigned char*>(mesh.vertices.data());
  for (std::size_t i = 0; i < std::size_t(mesh.vertices.size()) * sizeof(double); ++i)
    h = (h ^ bytes[i]) * 1099511628211ull;
  return h;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s MESH.ply POINTS.ply SPACING [REPEATS] [--fans]\n", argv[0]);
    return 2;
  }
  try {
    const Mesh mesh = read_mesh(argv[1]);
    const OrientedPoints points = read_oriented_points(argv[2]);
    const double spacing = std::stod(argv[3]);
    int repeats = 5;
    bool fans = false;
    for (int a = 4; a < argc; ++a) {
      if (std::strcmp(argv[a], "--fans") == 0)
        fans = true;
      else
        repeats = std::max(1, std::stoi(argv[a]));
    }
    ContactProjectionOptions o = local_projection_options();
    if (fans) o.robust_rounds = 1;
    const ContactProjector projector(points.points, points.normals, Eigen::VectorXd(), spacing, o);
    std::vector<double> seconds;
    Mesh projected;
    ContactProjectionStats stats;
    for (int r = 0; r < repeats; ++r) {
      projected = mesh;
      const auto start = std::chrono::steady_clock::now();
      stats = projector.project(projected);
      seconds.push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(seconds.begin(), seconds.end());
    std::printf(
        "{\"fastest\": %.4f, \"median\": %.4f, \"vertices\": %ld, \"moved\": %ld, "
        "\"checksum\": \"%016llx\"}\n",
        seconds.front(), seconds[seconds.size() / 2], long(mesh.vertices.rows()),
        stats.vertices_moved, static_cast<unsigned long long>(checksum(projected)));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "projection_timing: %s\n", e.what());
    return 1;
  }
  return 0;
}
