// Our PLY, OFF and OBJ readers on well-formed files of every flavour and on the hostile files that
// crashed or exhausted memory in third-party readers (issue 14).
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <string>

#include "io/mesh_files.h"
#include "sdfcontour/types.h"

using sdfcontour::Error;
using namespace sdfcontour::detail;

namespace {

std::string binary_ply(bool big_endian) {
  std::string s = std::string("ply\nformat binary_") + (big_endian ? "big" : "little") +
                  "_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
                  "end_header\n";
  auto put = [&](const void* p, std::size_t n) {
    std::string bytes(static_cast<const char*>(p), n);
    if (big_endian) std::reverse(bytes.begin(), bytes.end());
    s += bytes;
  };
  for (int v = 0; v < 3; ++v) {
    const float x = 0.5f * float(v), y = -1.25f;
    const double z = 1.0 / 3.0 + v;
    put(&x, 4), put(&y, 4), put(&z, 8);
  }
  const unsigned char three = 3;
  s += char(three);
  for (int i : {0, 1, 2}) put(&i, 4);
  return s;
}

// Parsing must end (with an Error) quickly and without a large allocation.
template <class Parse>
void expect_refused(Parse parse, const std::string& bytes, const char* needle) {
  const auto start = std::chrono::steady_clock::now();
  try {
    parse(bytes, "hostile");
    ADD_FAILURE() << "accepted: " << needle;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

}  // namespace

TEST(MeshFiles, PlyInEveryFormat) {
  for (bool big : {false, true}) {
    const PolygonSoup s = parse_ply(binary_ply(big), "b.ply");
    ASSERT_EQ(s.points.size(), 3u);
    EXPECT_EQ(s.points[2][0], 1.0);
    EXPECT_EQ(s.points[1][1], -1.25);
    EXPECT_EQ(s.points[1][2], 1.0 / 3.0 + 1);
    ASSERT_EQ(s.polygons.size(), 1u);
    EXPECT_EQ(s.polygons[0], (std::vector<long>{0, 1, 2}));
    EXPECT_TRUE(s.normals.empty());
  }
  const PolygonSoup a = parse_ply(
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nelement vertex 2\r\nproperty float x\r\n"
      "property float y\r\nproperty float z\r\nproperty float nx\r\nproperty float ny\r\n"
      "property float nz\r\nproperty uchar red\r\nelement edge 1\r\nproperty int a\r\n"
      "end_header\r\n0.1 2 3 0 0 1 255\r\n4 5 6 1 0 0 7\r\n9\r\n",
      "a.ply");
  ASSERT_EQ(a.points.size(), 2u);
  EXPECT_EQ(a.points[0][0], double(0.1f));  // a float property holds a float
  ASSERT_EQ(a.normals.size(), 2u);
  EXPECT_EQ(a.normals[1][0], 1.0);
  // ASCII items shorter than their binary size (double properties written as "0"): all read.
  std::string many = "ply\nformat ascii 1.0\nelement vertex 100\n";
  for (const char* c : {"x", "y", "z", "nx", "ny", "nz"})
    many += std::string("property double ") + c + "\n";
  many += "end_header\n";
  for (int i = 0; i < 100; ++i) many += "0 0 0 0 0 1\n";
  EXPECT_EQ(parse_ply(many, "short.ply").points.size(), 100u);
}

TEST(MeshFiles, HostilePlyIsRefused) {
  auto ply = [](const std::string& b, const std::string& n) { return parse_ply(b, n); };
  // A property before any element crashed CGAL's reader.
  expect_refused(ply, "ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\nend_header\n1\n",
                 "before any element");
  // A huge list count in a few hundred bytes made CGAL allocate without bound.
  std::string huge =
      "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uint int "
      "vertex_indices\nend_header\n";
  const unsigned count = 0xfffffff0u;
  huge.append(reinterpret_cast<const char*>(&count), 4);
  huge.append(200, '\1');
  expect_refused(ply, huge, "list longer than the file");
  expect_refused(ply,
                 "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty "
                 "double x\nproperty double y\nproperty double z\nend_header\n",
                 "more items than the file holds");
  std::string truncated = binary_ply(false);
  truncated.resize(truncated.size() - 3);
  expect_refused(ply, truncated, "ends before");
  expect_refused(ply,
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float "
                 "y\nproperty float z\nend_header\nnan 0 0\n",
                 "not a finite number");
  expect_refused(ply, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "end_header");
  expect_refused(ply, "PK\3\4", "start with 'ply'");
  // Found by fuzzing: a second vertex element (without normals) after one with them.
  expect_refused(ply,
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float "
                 "y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float "
                 "nz\nelement vertex 1\nproperty float x\nproperty float y\nproperty float "
                 "z\nend_header\n0 0 0 0 0 1\n1 1 1\n",
                 "two 'vertex' elements");
}

TEST(MeshFiles, OffWithColoursAndNormals) {
  // Colours after the coordinates (read past a heap buffer in CGAL's reader) are skipped.
  const PolygonSoup c = parse_off(
      "COFF\n# a comment\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
      "0 0 1 9 9 9 9\n3 0 1 2 255 255 255\n4 0 1 3 2\n",
      "c.off");
  ASSERT_EQ(c.points.size(), 4u);
  EXPECT_EQ(c.points[3][2], 1.0);
  ASSERT_EQ(c.polygons.size(), 2u);
  EXPECT_EQ(c.polygons[1], (std::vector<long>{0, 1, 3, 2}));
  const PolygonSoup n = parse_off("NOFF 1 0 0\n1 2 3 0 0 1\n", "n.off");
  ASSERT_EQ(n.normals.size(), 1u);
  EXPECT_EQ(n.normals[0][2], 1.0);
  auto off = [](const std::string& b, const std::string& name) { return parse_off(b, name); };
  expect_refused(off, "OFF\n900000000 1 0\n0 0 0\n", "more vertices or faces");
  expect_refused(off, "OFF\n1 1 0\n0 0 0\n2000000000 0 0 0\n", "vertex count");
  expect_refused(off, "OFF\n1 0 0\n0 inf 0\n", "not a finite number");
  expect_refused(off, "OFF\n-1 0 0\n", "counts");
}

TEST(MeshFiles, ObjIndicesAndFormats) {
  const PolygonSoup o = parse_obj(
      "# cube corner\nv 0 0 0\nv 1 0 0\nvn 0 0 1\nvt 0 0\nv 0 1 0\n  f 1/1/1 2//1 3\nf -3 -2 -1\n"
      "g group\nusemtl m\n",
      "o.obj");
  ASSERT_EQ(o.points.size(), 3u);
  ASSERT_EQ(o.polygons.size(), 2u);
  EXPECT_EQ(o.polygons[0], (std::vector<long>{0, 1, 2}));
  EXPECT_EQ(o.polygons[1], (std::vector<long>{0, 1, 2}));
  auto obj = [](const std::string& b, const std::string& name) { return parse_obj(b, name); };
  expect_refused(obj, "v 0 0\n", "bad coordinate");
  expect_refused(obj, "v 0 0 0\nf 0 1 2\n", "bad vertex index");
  expect_refused(obj, "v 1e999 0 0\n", "bad coordinate");
}
