#include <cmath>
#include <filesystem>
#include <fstream>

#include "sdfcontour/io/npy.h"
#include "test_support.h"

using namespace sdfcontour;

namespace {

// Writes a .npy by hand: `descr` and `fortran` go into the header verbatim, `payload` after it.
void write_raw_npy(const std::string& path, const std::string& descr, const std::string& fortran,
                   const std::string& shape, const std::string& payload) {
  std::string header =
      "{'descr': '" + descr + "', 'fortran_order': " + fortran + ", 'shape': " + shape + ", }";
  header.append((64 - (10 + header.size() + 1) % 64) % 64, ' ');
  header += '\n';
  std::ofstream out(path, std::ios::binary);
  out.write("\x93NUMPY\x01\x00", 8);
  const char len[2] = {char(header.size() & 0xff), char(header.size() >> 8)};
  out.write(len, 2);
  out << header << payload;
}

std::string floats_bytes(const std::vector<float>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
}

}  // namespace

TEST(Npy, RoundTripFloat64) {
  const auto dir = test::temp_dir("npy_roundtrip");
  const std::string path = (dir / "a.npy").string();
  std::vector<double> data(2 * 3 * 4);
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = 0.25 * double(i) - 1.5;
  write_npy(path, {2, 3, 4}, data);
  const NpyArray a = read_npy(path);
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{2, 3, 4}));
  EXPECT_EQ(a.data, data);
}

// Values written straight from a buffer: float64 exactly, float32 as each value's nearest float
// (converted in chunks, so past one chunk of 2^20 values too); a count that is not the shape's
// product is a bug of the caller.
TEST(Npy, WritesABufferAsFloat64OrFloat32) {
  const auto dir = test::temp_dir("npy_buffer");
  const std::size_t n = (std::size_t(1) << 20) + 8;
  std::vector<double> data(n);
  for (std::size_t i = 0; i < n; ++i) data[i] = std::sin(0.001 * double(i)) / 3;
  write_npy((dir / "d.npy").string(), {n}, data.data(), n, ScalarType::Float64);
  EXPECT_EQ(read_npy((dir / "d.npy").string()).data, data);
  write_npy((dir / "f.npy").string(), {8, n / 8}, data.data(), n, ScalarType::Float32);
  const NpyArray f = read_npy((dir / "f.npy").string());
  EXPECT_EQ(f.shape, (std::vector<std::size_t>{8, n / 8}));
  ASSERT_EQ(f.data.size(), n);
  std::size_t same = 0;
  for (std::size_t i = 0; i < n; ++i) same += f.data[i] == double(float(data[i]));
  EXPECT_EQ(same, n);
  EXPECT_THROW(write_npy((dir / "x.npy").string(), {3}, data.data(), 2, ScalarType::Float32),
               InternalError);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.npy"));
}

TEST(Npy, ReadsFloat32AndGridLayout) {
  const auto dir = test::temp_dir("npy_f4");
  const std::string path = (dir / "g.npy").string();
  std::vector<float> v(2 * 3 * 4);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float(i) - 5.0f;
  write_raw_npy(path, "<f4", "False", "(2, 3, 4)", floats_bytes(v));
  const SdfInput in = sdf_input_from_npy(map_npy(path), Bounds{});
  ASSERT_NE(grid_view_of(in), nullptr);
  // Viewed in place, as float32.
  const GridView& g = *grid_view_of(in);
  EXPECT_EQ(g.type, ScalarType::Float32);
  EXPECT_EQ(g.value(g.index(1, 2, 3)), double(v[(1 * 3 + 2) * 4 + 3]));
  // a[i,j,k] is at min + (i*hx, j*hy, k*hz) with h = 2/(n-1).
  const Eigen::Vector3d p = g.point(1, 2, 3);
  EXPECT_DOUBLE_EQ(p.x(), 1.0);
  EXPECT_DOUBLE_EQ(p.y(), 1.0);
  EXPECT_DOUBLE_EQ(p.z(), 1.0);
  EXPECT_DOUBLE_EQ(g.point(0, 1, 1).y(), 0.0);
  EXPECT_DOUBLE_EQ(g.point(0, 1, 1).z(), -1.0 + 2.0 / 3.0);
}

TEST(Npy, ScatteredSamples) {
  const auto dir = test::temp_dir("npy_scattered");
  const std::string path = (dir / "s.npy").string();
  write_npy(path, {4, 4}, {0, 0, 0, -1, 1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1});
  const SdfInput in = sdf_input_from_array(read_npy(path), Bounds{});
  ASSERT_TRUE(std::holds_alternative<ScatteredInput>(in));
  const Samples& samples = std::get<ScatteredInput>(in).samples;
  EXPECT_EQ(samples.points.rows(), 4);
  EXPECT_EQ(samples.points(2, 1), 1.0);
  EXPECT_EQ(samples.values[0], -1.0);
}

TEST(Npy, RejectsBadFiles) {
  const auto dir = test::temp_dir("npy_bad");
  auto expect_error = [&](const std::string& name, const std::string& needle) {
    try {
      sdf_input_from_npy(map_npy((dir / name).string()), Bounds{});
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << name << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "multi-line message";
    }
  };
  std::vector<float> eight(8, 1.0f);
  write_raw_npy((dir / "fortran.npy").string(), "<f4", "True", "(2, 2, 2)", floats_bytes(eight));
  write_raw_npy((dir / "int.npy").string(), "<i8", "False", "(2, 2, 2)", std::string(64, '\0'));
  write_raw_npy((dir / "big_endian.npy").string(), ">f8", "False", "(2, 2, 2)",
                std::string(64, '\0'));
  write_raw_npy((dir / "truncated.npy").string(), "<f4", "False", "(4, 4, 4)", floats_bytes(eight));
  write_raw_npy((dir / "shape.npy").string(), "<f4", "False", "(4, 2)", floats_bytes(eight));
  write_raw_npy((dir / "few.npy").string(), "<f4", "False", "(2, 4)", floats_bytes(eight));
  write_raw_npy((dir / "trailing.npy").string(), "<f4", "False", "(2, 2)", floats_bytes(eight));
  write_raw_npy((dir / "empty.npy").string(), "<f4", "False", "(0, 0, 0)", "");
  write_raw_npy((dir / "flat.npy").string(), "<f4", "False", "(1, 2, 4)", floats_bytes(eight));
  std::vector<float> nan = eight;
  nan[3] = std::numeric_limits<float>::quiet_NaN();
  write_raw_npy((dir / "nan.npy").string(), "<f4", "False", "(2, 2, 2)", floats_bytes(nan));
  std::vector<float> inf = eight;
  inf[5] = std::numeric_limits<float>::infinity();
  write_raw_npy((dir / "inf.npy").string(), "<f4", "False", "(2, 2, 2)", floats_bytes(inf));
  std::ofstream((dir / "junk.npy").string()) << "this is not numpy";
  // Hostile headers: a 60 KB field (a regex parser overflowed its stack on it), a shape whose
  // product overflows 64 bits, a negative dimension, a header longer than any real one.
  write_raw_npy((dir / "long_field.npy").string(), std::string(60000, 'f'), "False", "(2, 2, 2)",
                floats_bytes(eight));
  write_raw_npy((dir / "overflow.npy").string(), "<f4", "False", "(4294967296, 4294967296, 2)",
                floats_bytes(eight));
  write_raw_npy((dir / "huge_dim.npy").string(), "<f4", "False", "(99999999999999999999999, 2, 2)",
                floats_bytes(eight));
  write_raw_npy((dir / "negative.npy").string(), "<f4", "False", "(-1, 2, 4)", floats_bytes(eight));
  write_raw_npy((dir / "no_shape.npy").string(), "<f4", "False", "", floats_bytes(eight));
  expect_error("fortran.npy", "Fortran order");
  expect_error("int.npy", "dtype");
  expect_error("big_endian.npy", "dtype");
  expect_error("truncated.npy", "truncated");
  expect_error("shape.npy", "neither a grid");
  expect_error("few.npy", "at least 4 samples");
  expect_error("trailing.npy", "corrupt");
  expect_error("empty.npy", "at least 2");
  expect_error("flat.npy", "at least 2");
  expect_error("nan.npy", "NaN");
  expect_error("inf.npy", "NaN, infinite");
  expect_error("junk.npy", "not a .npy file");
  expect_error("long_field.npy", "dtype");
  expect_error("overflow.npy", "truncated");
  expect_error("huge_dim.npy", "64 bits");
  expect_error("negative.npy", "non-negative integers");
  expect_error("no_shape.npy", "not a valid .npy");
  expect_error("missing.npy", "cannot read");
}
