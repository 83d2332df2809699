// Model I/O (PCL hidden in src/): float64 round trips through .ply and .pcd, an OBJ mesh whose
// area-weighted vertex normals are known analytically (an octahedron: the normal at vertex +-e_i is
// +-e_i), and the typed errors naming the file. The Python tests add real meshes and normal estimation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <unistd.h>

#include "expect_error.hpp"
#include "model_file_test.hpp"
#include "surfeledit/core/model_io.hpp"

namespace surfeledit {
namespace {

namespace fs = std::filesystem;

class ModelIo : public testing_util::ModelFileTest {};

SurfelArrays random_surfels(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SurfelArrays a;
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  a.radii.resize(n);
  a.colors.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    // Large offsets: only float64 storage keeps these positions exact.
    a.positions.row(i) << 1e6 + u(rng), -3e5 + u(rng), 7.0 + 1e-9 * u(rng);
    Vec3 nrm(u(rng), u(rng), u(rng) + 2.0);
    a.normals.row(i) = nrm.normalized().transpose();
    a.radii[i] = 0.01 + 0.001 * (u(rng) + 1.0);
    a.colors.row(i) << std::uint8_t(i % 256), std::uint8_t((7 * i) % 256), std::uint8_t(255 - i % 256);
  }
  return a;
}

// Saves `a` as `file`, loads it back and compares: positions bit-identical (float64 on disk), normals and
// radii to float32 precision, colours exactly when saved.
void expect_round_trip(const SurfelArrays& a, const std::string& file) {
  save_surfels(file, a);
  const SurfelArrays b = load_surfels(file);
  ASSERT_EQ(b.positions.rows(), a.positions.rows());
  EXPECT_EQ(b.positions, a.positions);
  EXPECT_LT((b.normals - a.normals).cwiseAbs().maxCoeff(), 1e-6);
  ASSERT_EQ(b.radii.size(), a.radii.size());
  EXPECT_LT(((b.radii - a.radii).array() / a.radii.array()).abs().maxCoeff(), 1e-6);
  ASSERT_EQ(b.colors.rows(), a.colors.rows());
  EXPECT_EQ(b.colors, a.colors);
}

TEST_F(ModelIo, RoundTripKeepsFloat64PositionsInPlyAndPcd) {
  const SurfelArrays a = random_surfels(300, 5);
  expect_round_trip(a, path("cloud.pcd"));
  SurfelArrays plain = a;
  plain.colors.resize(0, 3);
  expect_round_trip(plain, path("cloud.ply"));
}

// Clip lines of a merge's crease are extra float64 vertex properties: they come back bit for bit.
TEST_F(ModelIo, ClipLinesRoundTripAsExtraProperties) {
  SurfelArrays a = random_surfels(200, 9);
  a.colors.resize(0, 3);  // PLY with rgb: the known bug below
  SurfelModel m = SurfelModel::from_arrays(a);
  Points points(2, 3), dirs(2, 3);
  points << 1e6 + 0.125, -3e5, 7.0, 1e6 - 0.5, -3e5 + 1e-7, 7.0;
  const Vec3 n3 = m.normals().row(3).transpose(), n150 = m.normals().row(150).transpose();
  dirs.row(0) = n3.cross(Vec3(1, 0, 0)).normalized().transpose();
  dirs.row(1) = n150.cross(Vec3(0, 1, 0)).normalized().transpose();
  m.set_clips({3, 150}, points, dirs);
  ASSERT_TRUE(m.has_clips());
  for (const char* file : {"clipped.ply", "clipped.pcd"}) {
    SCOPED_TRACE(file);
    save_surfels(path(file), m.arrays());
    const SurfelArrays b = load_surfels(path(file));
    EXPECT_EQ(b.positions, m.positions());
    ASSERT_EQ(b.clip_points.rows(), m.size());
    EXPECT_EQ(b.clip_points, m.clip_points());
    EXPECT_EQ(b.clip_dirs, m.clip_dirs());
    EXPECT_TRUE(SurfelModel::from_arrays(b).has_clips());
  }
  // A model without clip lines writes none.
  save_surfels(path("plain.ply"), a);
  EXPECT_EQ(load_surfels(path("plain.ply")).clip_dirs.rows(), 0);
}

// A .ply saved with colours loads with them (PCL's writer once wrote 4 bytes for 3 declared uchar
// properties, and loading threw bad_alloc). The file agrees with its header: vertex stride checked.
TEST_F(ModelIo, PlyRoundTripKeepsColours) {
  expect_round_trip(random_surfels(300, 5), path("cloud.ply"));
  std::ifstream in(path("cloud.ply"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("property uchar red\nproperty uchar green\nproperty uchar blue\n"), std::string::npos);
}

TEST_F(ModelIo, ObjOctahedronGivesVertexSurfelsWithAnalyticNormals) {
  const std::string file = path("octahedron.obj");
  {
    std::ofstream out(file);
    out << "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\nv 5 5 5\n";  // vertex 7: unreferenced
    // Counter-clockwise seen from outside: (x, y, z) in each octant with the right orientation.
    out << "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  }
  const SurfelArrays a = load_surfels(file);
  ASSERT_EQ(a.positions.rows(), 6);  // the unreferenced vertex is dropped
  for (Eigen::Index i = 0; i < 6; ++i) {
    const Vec3 p = a.positions.row(i).transpose();
    EXPECT_NEAR(p.norm(), 1.0, 1e-12);
    // By symmetry the four incident faces' normals sum to a multiple of the vertex direction.
    EXPECT_LT((a.normals.row(i).transpose() - p).norm(), 1e-6) << "vertex " << i;
  }
}

// A mesh vertex that is not finite is refused under the field "path", naming the file and the vertex.
TEST_F(ModelIo, ObjWithANonFiniteVertexIsRefusedNamingTheFile) {
  const std::string file = path("infinite.obj");
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n";
  const std::string msg = testing_util::expect_error([&] { load_surfels(file); }, ErrorCode::InvalidArgument, "path");
  EXPECT_NE(msg.find("infinite.obj"), std::string::npos) << msg;
  EXPECT_NE(msg.find("vertices"), std::string::npos) << msg;
}

void expect_load_error(const std::string& file, ErrorCode code) {
  const std::string msg = testing_util::expect_error([&] { load_surfels(file); }, code, "path");
  EXPECT_NE(msg.find(fs::path(file).filename().string()), std::string::npos) << msg;
}

TEST_F(ModelIo, ErrorsAreTypedAndNameTheFile) {
  expect_load_error(path("missing.ply"), ErrorCode::NotFound);
  expect_load_error(dir_.string(), ErrorCode::Io);  // a directory
  {
    std::ofstream(path("garbage.pcd")) << "this is not a point cloud\n";
  }
  expect_load_error(path("garbage.pcd"), ErrorCode::Io);
  {
    std::ofstream(path("points.vtk")) << "1 2 3\n";
  }
  expect_load_error(path("points.vtk"), ErrorCode::InvalidArgument);
  testing_util::expect_error([&] { save_surfels(path("out.obj"), random_surfels(3, 1)); },
                             ErrorCode::InvalidArgument, "path");
  EXPECT_FALSE(fs::exists(path("out.obj")));
}

// A text point set (.xyz, .pwn): x y z [nx ny nz] per line, blanks or commas between, '#' comments and empty lines
// skipped, CRLF endings; positions exact (printed with 17 digits), normals as given up to normalisation.
TEST_F(ModelIo, TextPointSetsLoadWithOrWithoutNormals) {
  const SurfelArrays a = random_surfels(50, 3);
  {
    std::ofstream out(path("cloud.pwn"));
    out << "# x y z nx ny nz\r\n\n";
    out.precision(17);
    for (Index i = 0; i < a.positions.rows(); ++i) {
      out << a.positions(i, 0) << (i % 2 ? ", " : " ") << a.positions(i, 1) << "\t" << a.positions(i, 2) << " "
          << a.normals(i, 0) << " " << a.normals(i, 1) << " " << a.normals(i, 2) << (i % 3 ? "\n" : "\r\n");
    }
  }
  const SurfelArrays b = load_surfels(path("cloud.pwn"));
  EXPECT_EQ(b.positions, a.positions);
  EXPECT_LT((b.normals - a.normals).cwiseAbs().maxCoeff(), 1e-12);
  {
    std::ofstream out(path("cloud.XYZ"));  // the extension in any case, positions only: normals estimated
    out.precision(17);
    for (Index i = 0; i < a.positions.rows(); ++i)
      out << a.positions(i, 0) << " " << a.positions(i, 1) << " " << a.positions(i, 2) << "\n";
  }
  const SurfelArrays c = load_surfels(path("cloud.XYZ"));
  EXPECT_EQ(c.positions, a.positions);
  ASSERT_EQ(c.normals.rows(), a.positions.rows());
  EXPECT_LT((c.normals.rowwise().norm().array() - 1.0).abs().maxCoeff(), 1e-9);
}

// Each malformed text point set is refused with its own typed error naming the file (and the line, where one is at
// fault); a file of more lines than the point limit is refused before PCL's reader allocates for them.
TEST_F(ModelIo, MalformedTextPointSetsAreRefused) {
  expect_refused({
      {"four.xyz", "0 0 0\n1 1 1\n1 2 3 4\n", ErrorCode::InvalidArgument, "line 3"},
      {"first.xyz", "1 2\n", ErrorCode::InvalidArgument, "line 1"},
      {"mixed.pwn", "0 0 0 0 0 1\n1 1 1\n", ErrorCode::InvalidArgument, "line 2"},
      {"word.xyz", "0 0 0\n1 one 1\n2 2 2\n", ErrorCode::InvalidArgument, "not a number"},
      {"empty.xyz", "# nothing\n\n", ErrorCode::InvalidArgument, "no points"},
      {"nan.xyz", "0 0 0\nnan 1 1\n2 2 2\n", ErrorCode::InvalidArgument, "non-finite"},
      {"nul.xyz", std::string("0 0 0\n1 1\0 1\n", 13), ErrorCode::Io, "NUL"},
  });
  {
    std::ofstream out(path("long.xyz"));
    out << "0 0 0 0 0 1\n";
    for (int i = 0; i < 2000; ++i) out << "\n";  // blank lines: PCL's reader would allocate a point for each
  }
  LoadParams limit;
  limit.max_points = 1000;
  testing_util::expect_error([&] { load_surfels(path("long.xyz"), limit); }, ErrorCode::TooLarge, "path");
  limit.max_points = 5000;
  EXPECT_EQ(load_surfels(path("long.xyz"), limit).positions.rows(), 1);
}

}  // namespace
}  // namespace surfeledit
