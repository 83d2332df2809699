// Mesh files read with CGAL (server/core/src/mesh_files.cpp, model_headers.cpp): an octahedron as ASCII OFF, ASCII
// STL and binary STL gives the analytic vertex normals (at vertex +-e_i the normal is +-e_i); OFF keeps float64
// coordinates; lying counts, binary OFF, broken STL and out-of-range faces are refused with typed errors naming the
// file, before anything is allocated for what the file cannot hold.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "surfeledit/core/model_io.hpp"
#include "model_file_test.hpp"

namespace surfeledit {
namespace {

class MeshFiles : public testing_util::ModelFileTest {};

const double kOctahedron[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
// Counter-clockwise seen from outside (0-based).
const int kOctahedronFaces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                    {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};

std::string octahedron_off() {
  std::string s = "OFF\n# an octahedron\n7 8 0\n";
  for (const auto& v : kOctahedron) s += std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
  s += "5 5 5\n";  // unreferenced: dropped
  for (const auto& f : kOctahedronFaces) s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
  return s;
}

std::string octahedron_ascii_stl() {
  std::string s = "solid octahedron\n";
  for (const auto& f : kOctahedronFaces) {
    s += "facet normal 0 0 0\nouter loop\n";
    for (int k : f) s += "vertex " + std::to_string(kOctahedron[k][0]) + " " + std::to_string(kOctahedron[k][1]) + " " + std::to_string(kOctahedron[k][2]) + "\n";
    s += "endloop\nendfacet\n";
  }
  return s + "endsolid octahedron\n";
}

// Binary STL: 80 header bytes, the triangle count, then per triangle a normal, three corners (float32) and 2 bytes.
std::string binary_stl(const std::vector<std::array<float, 9>>& triangles) {
  std::string s(80, ' ');
  const std::uint32_t n = static_cast<std::uint32_t>(triangles.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : triangles) {
    const float normal[3] = {0, 0, 0};
    s.append(reinterpret_cast<const char*>(normal), 12);
    s.append(reinterpret_cast<const char*>(t.data()), 36);
    s.append(2, '\0');
  }
  return s;
}

std::vector<std::array<float, 9>> octahedron_triangles() {
  std::vector<std::array<float, 9>> out;
  for (const auto& f : kOctahedronFaces) {
    std::array<float, 9> t{};
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) t[3 * c + d] = static_cast<float>(kOctahedron[f[c]][d]);
    out.push_back(t);
  }
  return out;
}

// `text` with Windows line ends.
std::string crlf(std::string text) {
  for (std::size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 2)) text.insert(at, "\r");
  return text;
}

void expect_octahedron(const SurfelArrays& a, const std::string& what) {
  ASSERT_EQ(a.positions.rows(), 6) << what;
  for (Eigen::Index i = 0; i < 6; ++i) {
    const Vec3 p = a.positions.row(i).transpose();
    EXPECT_NEAR(p.norm(), 1.0, 1e-12) << what;
    EXPECT_LT((a.normals.row(i).transpose() - p).norm(), 1e-12) << what << ": vertex " << i;
  }
}

TEST_F(MeshFiles, AnOctahedronInOffAndStlGivesItsAnalyticNormals) {
  expect_octahedron(load_surfels(write("o.off", octahedron_off())), "OFF");
  expect_octahedron(load_surfels(write("o.stl", octahedron_ascii_stl())), "ASCII STL");
  expect_octahedron(load_surfels(write("b.stl", binary_stl(octahedron_triangles()))), "binary STL");
  // Windows line ends.
  expect_octahedron(load_surfels(write("crlf.off", crlf(octahedron_off()))), "OFF with CRLF");
  expect_octahedron(load_surfels(write("crlf.stl", crlf(octahedron_ascii_stl()))), "ASCII STL with CRLF");
  // A binary STL whose 80-byte header starts with "solid" is still binary: its size says so.
  std::string solid = binary_stl(octahedron_triangles());
  solid.replace(0, 6, "solid ");
  expect_octahedron(load_surfels(write("s.stl", solid)), "binary STL starting with 'solid'");
}

TEST_F(MeshFiles, OffCoordinatesKeepFloat64) {
  const double x = 0.12345678901234567, y = -3.0000000000000004, z = 1e-17;
  const std::string text = "OFF\n3 1 0\n0.12345678901234567 -3.0000000000000004 1e-17\n1 0 0\n0 1 0\n3 0 1 2\n";
  const SurfelArrays a = load_surfels(write("t.off", text));
  ASSERT_EQ(a.positions.rows(), 3);
  EXPECT_EQ(a.positions(0, 0), x);
  EXPECT_EQ(a.positions(0, 1), y);
  EXPECT_EQ(a.positions(0, 2), z);
}

// OBJ goes through CGAL's reader first: float64, so a small model 1e6 from the origin keeps its shape (PCL's float32
// would move every vertex by up to 0.03 here, 30 times the model's size).
TEST_F(MeshFiles, ObjKeepsFloat64FarFromTheOrigin) {
  const double c[3] = {1e6, -2e6, 3e6}, s = 1e-3;
  char line[128];
  std::string text;
  std::vector<Vec3> written;
  for (const auto& v : kOctahedron) {
    const Vec3 p(c[0] + s * v[0], c[1] + s * v[1], c[2] + s * v[2]);
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
    text += line;
    written.push_back(p);
  }
  for (const auto& f : kOctahedronFaces) text += "f " + std::to_string(f[0] + 1) + " " + std::to_string(f[1] + 1) + " " + std::to_string(f[2] + 1) + "\n";
  const SurfelArrays a = load_surfels(write("far.obj", crlf(text)));  // with Windows line ends
  ASSERT_EQ(a.positions.rows(), 6);
  for (Eigen::Index i = 0; i < 6; ++i) {
    EXPECT_EQ(a.positions.row(i).transpose(), written[static_cast<std::size_t>(i)]) << "vertex " << i;
    const Vec3 axis(kOctahedron[i][0], kOctahedron[i][1], kOctahedron[i][2]);
    EXPECT_LT((a.normals.row(i).transpose() - axis).norm(), 1e-9) << "vertex " << i;
  }
}

// What CGAL's OBJ reader does not take goes to PCL's: a point set without faces, faces with tab-separated indices.
TEST_F(MeshFiles, ObjWithoutFacesOrWithTabsStillLoads) {
  std::string grid;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) grid += "v " + std::to_string(0.1 * i) + " " + std::to_string(0.1 * j) + " 0\n";
  const SurfelArrays points = load_surfels(write("grid.obj", grid));
  ASSERT_EQ(points.positions.rows(), 36);
  for (Eigen::Index i = 0; i < 36; ++i) EXPECT_NEAR(std::abs(points.normals(i, 2)), 1.0, 1e-9) << "point " << i;
  std::string tabs;
  for (const auto& v : kOctahedron) tabs += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
  for (const auto& f : kOctahedronFaces) tabs += "f\t" + std::to_string(f[0] + 1) + "\t" + std::to_string(f[1] + 1) + "\t" + std::to_string(f[2] + 1) + "\n";
  expect_octahedron(load_surfels(write("tabs.obj", tabs)), "OBJ with tabs");
}

// An OFF file without faces is a point set: NOFF's normals as written, else estimated from the neighbours.
TEST_F(MeshFiles, OffWithoutFacesIsAPointSet) {
  std::string noff = "NOFF\n4 0 0\n";
  const double normals[4][3] = {{0, 0, 1}, {0.6, 0, 0.8}, {0, -1, 0}, {-0.28, 0.96, 0}};
  for (int i = 0; i < 4; ++i)
    noff += std::to_string(i) + " 0.5 -1 " + std::to_string(normals[i][0]) + " " + std::to_string(normals[i][1]) + " " +
            std::to_string(normals[i][2]) + "\n";
  const SurfelArrays written = load_surfels(write("n.off", noff));
  ASSERT_EQ(written.positions.rows(), 4);
  for (Eigen::Index i = 0; i < 4; ++i) {
    EXPECT_EQ(written.positions.row(i), Eigen::RowVector3d(static_cast<double>(i), 0.5, -1.0));
    EXPECT_LT((written.normals.row(i) - Eigen::RowVector3d(normals[i][0], normals[i][1], normals[i][2])).norm(), 1e-12);
  }
  std::string grid = "OFF\n36 0 0\n";
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) grid += std::to_string(0.1 * i) + " " + std::to_string(0.1 * j) + " 2\n";
  const SurfelArrays estimated = load_surfels(write("grid.off", grid));
  ASSERT_EQ(estimated.positions.rows(), 36);
  for (Eigen::Index i = 0; i < 36; ++i) EXPECT_NEAR(std::abs(estimated.normals(i, 2)), 1.0, 1e-9) << "point " << i;
  expect_refused({{"none.off", "OFF\n0 0 0\n", ErrorCode::InvalidArgument, "no points"}});
}

TEST_F(MeshFiles, BrokenFilesAreRefusedNamingTheFile) {
  std::string nan_stl = binary_stl(octahedron_triangles());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(&nan_stl[84 + 50 * 3 + 12 + 4], &nan, 4);  // triangle 3, first corner's y
  std::string short_stl = binary_stl(octahedron_triangles());
  short_stl.pop_back();
  expect_refused({
      {"lying.off", "OFF\n2000000000 1 0\n0 0 0\n", ErrorCode::Io, "2000000000 vertices"},
      {"faces.off", "OFF\n3 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ErrorCode::Io, "faces"},
      {"huge_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2000000000 0 1 2\n", ErrorCode::InvalidArgument, "a face of"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", ErrorCode::Io, "OFF"},
      {"binary.off", "OFF BINARY\n3 1 0\n", ErrorCode::Io, "binary OFF"},
      {"dim.off", "nOFF\n4\n3 1 0\n", ErrorCode::Io, "dimension"},
      {"nomagic.off", "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ErrorCode::Io, "no OFF keyword"},
      {"counts.off", "OFF\n3 -1 0\n", ErrorCode::Io, "not a count"},
      {"flat.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n", ErrorCode::InvalidArgument, "no usable vertex"},
      {"nan.stl", nan_stl, ErrorCode::Io, "non-finite"},
      {"short.stl", short_stl, ErrorCode::Io, "neither ASCII"},
      {"cut.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0", ErrorCode::Io, "STL"},
  });
}

// 4OFF: homogeneous coordinates, divided by w. A w of 0 is refused: by CGAL's assertion where assertions are on (Io),
// as a non-finite vertex where they are off (InvalidArgument).
TEST_F(MeshFiles, HomogeneousOffDividesByWAndRefusesWZero) {
  const SurfelArrays a = load_surfels(write("h.off", "4OFF\n3 1 0\n0 0 0 2\n4 0 0 2\n0 6 0 3\n3 0 1 2\n"));
  ASSERT_EQ(a.positions.rows(), 3);
  EXPECT_EQ(a.positions.row(1), Eigen::RowVector3d(2, 0, 0));
  EXPECT_EQ(a.positions.row(2), Eigen::RowVector3d(0, 2, 0));
  const std::string file = write("w0.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 0\n0 1 0 1\n3 0 1 2\n");
  try {
    load_surfels(file);
    ADD_FAILURE() << "a vertex with w = 0 loaded";
  } catch (const Error& e) {
    EXPECT_TRUE(e.code() == ErrorCode::Io || e.code() == ErrorCode::InvalidArgument) << e.what();
    EXPECT_EQ(e.field(), "path");
    EXPECT_NE(std::string(e.what()).find("w0.off"), std::string::npos) << e.what();
  }
}

TEST_F(MeshFiles, ThePointLimitHoldsForOffAndStl) {
  LoadParams limit;
  limit.max_points = 5;
  testing_util::expect_error([&] { load_surfels(write("o.off", octahedron_off()), limit); }, ErrorCode::TooLarge, "path");
  testing_util::expect_error([&] { load_surfels(write("o.stl", octahedron_ascii_stl()), limit); }, ErrorCode::TooLarge,
                             "path");
  limit.max_points = 7;
  EXPECT_EQ(load_surfels(path("o.off"), limit).positions.rows(), 6);
  EXPECT_EQ(load_surfels(path("o.stl"), limit).positions.rows(), 6);
}

}  // namespace
}  // namespace surfeledit
