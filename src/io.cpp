#include "sdfcontour/io.h"

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/IO/read_ply_points.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <vector>

#include "atomic_file.h"

namespace sdfcontour {

namespace {

std::string extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || path.find_first_of('/', dot) != std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

void write_ply(std::ostream& out, const PointMatrix& vertices, const PointMatrix* normals,
               const TriangleMatrix* triangles, PlyFormat format) {
  out << "ply\nformat " << (format == PlyFormat::Binary ? "binary_little_endian" : "ascii")
      << " 1.0\n"
      << "comment written by sdfcontour\n"
      << "element vertex " << vertices.rows() << "\n"
      << "property double x\nproperty double y\nproperty double z\n";
  if (normals) out << "property double nx\nproperty double ny\nproperty double nz\n";
  if (triangles)
    out << "element face " << triangles->rows() << "\nproperty list uchar int vertex_indices\n";
  out << "end_header\n";
  if (format == PlyFormat::Binary) {
    for (Eigen::Index i = 0; i < vertices.rows(); ++i) {
      out.write(reinterpret_cast<const char*>(vertices.row(i).data()), 3 * sizeof(double));
      if (normals)
        out.write(reinterpret_cast<const char*>(normals->row(i).data()), 3 * sizeof(double));
    }
    if (triangles)
      for (Eigen::Index f = 0; f < triangles->rows(); ++f) {
        const unsigned char three = 3;
        out.write(reinterpret_cast<const char*>(&three), 1);
        out.write(reinterpret_cast<const char*>(triangles->row(f).data()), 3 * sizeof(int));
      }
  } else {
    out << std::setprecision(17);
    for (Eigen::Index i = 0; i < vertices.rows(); ++i) {
      out << vertices(i, 0) << ' ' << vertices(i, 1) << ' ' << vertices(i, 2);
      if (normals)
        out << ' ' << (*normals)(i, 0) << ' ' << (*normals)(i, 1) << ' ' << (*normals)(i, 2);
      out << '\n';
    }
    if (triangles)
      for (Eigen::Index f = 0; f < triangles->rows(); ++f)
        out << "3 " << (*triangles)(f, 0) << ' ' << (*triangles)(f, 1) << ' ' << (*triangles)(f, 2)
            << '\n';
  }
}

}  // namespace

void write_mesh(const std::string& path, const Mesh& mesh, PlyFormat ply_format) {
  const std::string ext = extension(path);
  if (ext != "ply" && ext != "obj")
    throw Error("cannot write a mesh to '" + path + "': use a .ply or .obj extension");
  AtomicFile file(path);
  if (ext == "ply") {
    write_ply(file.stream(), mesh.vertices, nullptr, &mesh.triangles, ply_format);
  } else {
    auto& out = file.stream();
    out << "# written by sdfcontour\n" << std::setprecision(17);
    for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
      out << "v " << mesh.vertices(i, 0) << ' ' << mesh.vertices(i, 1) << ' ' << mesh.vertices(i, 2)
          << '\n';
    for (Eigen::Index f = 0; f < mesh.triangles.rows(); ++f)
      out << "f " << mesh.triangles(f, 0) + 1 << ' ' << mesh.triangles(f, 1) + 1 << ' '
          << mesh.triangles(f, 2) + 1 << '\n';
  }
  file.commit();
}

Mesh read_mesh(const std::string& path) {
  const std::string ext = extension(path);
  if (ext != "obj" && ext != "ply" && ext != "off")
    throw Error("cannot read a mesh from '" + path + "': use a .obj, .ply or .off file");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw IoError("cannot read '" + path + "': " + std::strerror(errno));
  }
  using P = CGAL::Simple_cartesian<double>::Point_3;
  std::vector<P> points;
  std::vector<std::vector<std::size_t>> polygons;
  bool ok = false;
  try {
    ok = CGAL::IO::read_polygon_soup(path, points, polygons, CGAL::parameters::verbose(false));
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) throw Error("cannot parse '" + path + "' as a " + ext + " mesh");
  Mesh mesh;
  mesh.vertices.resize(Eigen::Index(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i) {
    mesh.vertices.row(Eigen::Index(i)) << points[i].x(), points[i].y(), points[i].z();
    if (!std::isfinite(points[i].x()) || !std::isfinite(points[i].y()) ||
        !std::isfinite(points[i].z()))
      throw Error("'" + path + "' has a vertex with a NaN or infinite coordinate");
  }
  std::vector<std::array<int, 3>> triangles;
  for (const auto& poly : polygons) {
    for (std::size_t v : poly)
      if (v >= points.size())
        throw Error("'" + path + "' has a face with an out-of-range vertex index");
    for (std::size_t q = 1; q + 1 < poly.size(); ++q)
      triangles.push_back({int(poly[0]), int(poly[q]), int(poly[q + 1])});
  }
  if (triangles.empty()) throw Error("'" + path + "' has no faces");
  mesh.triangles.resize(Eigen::Index(triangles.size()), 3);
  for (std::size_t f = 0; f < triangles.size(); ++f)
    mesh.triangles.row(Eigen::Index(f)) << triangles[f][0], triangles[f][1], triangles[f][2];
  return mesh;
}

void write_oriented_points(const std::string& path, const OrientedPoints& points,
                           PlyFormat ply_format) {
  if (extension(path) != "ply")
    throw Error("cannot write points to '" + path + "': use a .ply extension");
  AtomicFile file(path);
  write_ply(file.stream(), points.points, &points.normals, nullptr, ply_format);
  file.commit();
}

OrientedPoints read_oriented_points(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot read '" + path + "': " + std::strerror(errno));
  using K = CGAL::Simple_cartesian<double>;
  using PN = std::pair<K::Point_3, K::Vector_3>;
  std::vector<PN> pn;
  bool ok = false;
  try {
    ok = CGAL::IO::read_PLY_with_properties(
        in, std::back_inserter(pn),
        CGAL::make_ply_point_reader(CGAL::First_of_pair_property_map<PN>()),
        CGAL::make_ply_normal_reader(CGAL::Second_of_pair_property_map<PN>()));
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok) throw Error("cannot parse '" + path + "' as a PLY point cloud with x y z nx ny nz");
  OrientedPoints out;
  out.points.resize(Eigen::Index(pn.size()), 3);
  out.normals.resize(Eigen::Index(pn.size()), 3);
  for (std::size_t i = 0; i < pn.size(); ++i) {
    out.points.row(Eigen::Index(i)) << pn[i].first.x(), pn[i].first.y(), pn[i].first.z();
    out.normals.row(Eigen::Index(i)) << pn[i].second.x(), pn[i].second.y(), pn[i].second.z();
  }
  return out;
}

}  // namespace sdfcontour
