// Model file headers are checked against the file before any reader allocates (model_headers.hpp):
// lying counts, truncated data, garbage and non-regular files fail fast with bounded memory.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "expect_error.hpp"
#include "temp_dir_test.hpp"
#include "surfeledit/core/model_io.hpp"

namespace surfeledit {
namespace {

namespace fs = std::filesystem;

class ModelHeaders : public testing_util::TempDirTest {};

long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

// Expects `code` naming "path" within a second; returns the message.
std::string expect_fast_error(const std::string& file, ErrorCode code, LoadParams params = {}) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string msg = testing_util::expect_error([&] { load_surfels(file, params); }, code, "path");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0) << msg;
  return msg;
}

const std::string kLyingPcd =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2000000000\nHEIGHT 1\n"
    "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2000000000\nDATA ascii\n1 2 3\n";

TEST_F(ModelHeaders, PcdAnnouncingTwoBillionPointsInAFewBytesFailsAtOnce) {
  ASSERT_LT(kLyingPcd.size(), 200u);
  const long rss0 = peak_rss_kb();
  const std::string file = write("lying.pcd", kLyingPcd);
  EXPECT_NE(expect_fast_error(file, ErrorCode::Io).find("announces"), std::string::npos);
  LoadParams limited;
  limited.max_points = 20'000'000;
  EXPECT_NE(expect_fast_error(file, ErrorCode::TooLarge, limited).find("2000000000"), std::string::npos);
  EXPECT_LT(peak_rss_kb() - rss0, 64 * 1024);  // KiB: nothing near the announced 24 GB was allocated
  // Binary data shorter than announced, and a POINTS that contradicts WIDTH x HEIGHT.
  std::string truncated = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 10\nHEIGHT 1\n"
                          "POINTS 10\nDATA binary\n" + std::string(12 * 9, '\0');
  expect_fast_error(write("short.pcd", truncated), ErrorCode::Io);
  std::string contradicting = kLyingPcd;
  contradicting.replace(contradicting.find("POINTS 2000000000"), 17, "POINTS 1");
  expect_fast_error(write("points.pcd", contradicting), ErrorCode::Io);
}

TEST_F(ModelHeaders, PlyCountsMustFitTheFile) {
  const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex ";
  const std::string props = "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  // 4 vertices of 12 bytes need 48 bytes; 47 are there.
  expect_fast_error(write("short.ply", head + "4" + props + std::string(47, '\0')), ErrorCode::Io);
  // A count that overflows any multiplication.
  expect_fast_error(write("huge.ply", head + "18446744073709551615" + props), ErrorCode::Io);
  expect_fast_error(write("neg.ply", head + "-5" + props), ErrorCode::Io);
  // ascii: each value takes at least two bytes.
  expect_fast_error(write("ascii.ply", "ply\nformat ascii 1.0\nelement vertex 1000000" + props + "0 0 0\n"),
                    ErrorCode::Io);
  // A face list announced beyond the file.
  expect_fast_error(write("faces.ply", head + "3" + props.substr(0, props.size() - 11) +
                                           "element face 1000000\nproperty list uchar int vertex_indices\n"
                                           "end_header\n" + std::string(36, '\0')),
                    ErrorCode::Io);
  // No end_header within the first 64 KiB.
  expect_fast_error(write("endless.ply", "ply\nformat ascii 1.0\n" + std::string(70000, 'c') + "\n"), ErrorCode::Io);
}

TEST_F(ModelHeaders, AnHonestAsciiPlyLoads) {
  const std::string file = write("ok.ply",
                                 "ply\nformat ascii 1.0\ncomment hand-made\nelement vertex 3\nproperty double x\n"
                                 "property double y\nproperty double z\nproperty float nx\nproperty float ny\n"
                                 "property float nz\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 2 0 0 0 1\n");
  const SurfelArrays a = load_surfels(file);
  ASSERT_EQ(a.positions.rows(), 3);
  EXPECT_EQ(a.positions(2, 1), 2.0);
  EXPECT_EQ(a.normals(1, 2), 1.0);
  LoadParams limited;
  limited.max_points = 2;
  expect_fast_error(file, ErrorCode::TooLarge, limited);
}

TEST_F(ModelHeaders, SparseGibOfZerosFailsFastWithBoundedMemory) {
  const std::string file = (dir_ / "zeros.ply").string();
  {
    std::ofstream out(file, std::ios::binary);
  }
  fs::resize_file(file, std::uintmax_t(1) << 30);  // sparse: takes no disk space
  const long rss0 = peak_rss_kb();
  EXPECT_NE(expect_fast_error(file, ErrorCode::Io).find("not a PLY file"), std::string::npos);
  fs::rename(file, (dir_ / "zeros.pcd").string());
  expect_fast_error((dir_ / "zeros.pcd").string(), ErrorCode::Io);
  fs::rename((dir_ / "zeros.pcd").string(), (dir_ / "zeros.obj").string());
  expect_fast_error((dir_ / "zeros.obj").string(), ErrorCode::Io);
  EXPECT_LT(peak_rss_kb() - rss0, 16 * 1024);  // KiB
}

TEST_F(ModelHeaders, AFifoIsNotReadAndDoesNotBlock) {
  const std::string fifo = (dir_ / "x.ply").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(expect_fast_error(fifo, ErrorCode::Io).find("not a regular file"), std::string::npos);
}

}  // namespace
}  // namespace surfeledit
