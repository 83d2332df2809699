#include "mesh_files.hpp"

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Simple_cartesian.h>

#include <array>
#include <exception>
#include <fstream>
#include <iterator>

#include "file_error.hpp"

namespace surfeledit::mesh_files {
namespace {

using CgalPoint = CGAL::Simple_cartesian<double>::Point_3;
using CgalVector = CGAL::Simple_cartesian<double>::Vector_3;

// A face as CGAL's OFF reader fills it. The reader resizes a face to the count its line states before it reads the
// indices, so a lying count ("2000000000 0 1 2") would allocate for all of them: this face throws instead.
class BoundedFace {
 public:
  using value_type = std::size_t;
  void resize(std::size_t n) {
    if (n > kMaxFaceVertices) {
      throw Error(ErrorCode::InvalidArgument, "path",
                  "a face of " + std::to_string(n) + " vertices, more than " + std::to_string(kMaxFaceVertices));
    }
    v_.resize(n);
  }
  std::size_t size() const { return v_.size(); }
  std::size_t& operator[](std::size_t i) { return v_[i]; }
  const std::size_t& operator[](std::size_t i) const { return v_[i]; }
  std::vector<std::size_t>::const_iterator begin() const { return v_.begin(); }
  std::vector<std::size_t>::const_iterator end() const { return v_.end(); }

 private:
  std::vector<std::size_t> v_;
};

// CGAL's points or vectors as rows (#N by 3).
template <class Xyz>
Points rows_of(const std::vector<Xyz>& xyz) {
  Points out(static_cast<Eigen::Index>(xyz.size()), 3);
  for (std::size_t i = 0; i < xyz.size(); ++i) out.row(static_cast<Eigen::Index>(i)) << xyz[i].x(), xyz[i].y(), xyz[i].z();
  return out;
}

template <class Faces>
Soup soup_of(const std::vector<CgalPoint>& points, const Faces& faces) {
  Soup s;
  s.vertices = rows_of(points);
  s.faces.reserve(faces.size());
  for (const auto& f : faces) s.faces.emplace_back(f.begin(), f.end());
  return s;
}

}  // namespace

SurfelArrays surfels_of(const Soup& soup, const std::string& path) {
  const Points& v = soup.vertices;
  checked_in_file(path, [&] { require_finite(v, "vertices"); });
  Points acc = Points::Zero(v.rows(), 3);
  std::vector<bool> used(static_cast<std::size_t>(v.rows()), false);
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    const std::vector<std::int64_t>& idx = soup.faces[fi];
    for (const std::int64_t i : idx) {
      if (i < 0 || i >= v.rows()) {
        throw file_error(ErrorCode::InvalidArgument, path,
                         "face " + std::to_string(fi) + " refers to vertex " + std::to_string(i) +
                             " but there are only " + std::to_string(v.rows()));
      }
    }
    for (std::size_t k = 1; k + 1 < idx.size(); ++k) {
      const Vec3 a = v.row(idx[0]), b = v.row(idx[k]), c = v.row(idx[k + 1]);
      const Eigen::RowVector3d fn = (b - a).cross(c - a).transpose();
      acc.row(idx[0]) += fn;
      acc.row(idx[k]) += fn;
      acc.row(idx[k + 1]) += fn;
    }
    for (const std::int64_t i : idx) used[static_cast<std::size_t>(i)] = true;
  }
  IndexList keep;
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    if (used[static_cast<std::size_t>(i)] && acc.row(i).squaredNorm() > 0.0) keep.push_back(static_cast<Index>(i));
  if (keep.empty()) throw file_error(ErrorCode::InvalidArgument, path, "the mesh has no usable vertex");
  SurfelArrays a;
  a.positions.resize(static_cast<Eigen::Index>(keep.size()), 3);
  a.normals.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    a.positions.row(static_cast<Eigen::Index>(k)) = v.row(keep[k]);
    a.normals.row(static_cast<Eigen::Index>(k)) = acc.row(keep[k]).normalized();
  }
  return a;
}

Soup read_off(const std::string& path) {
  std::vector<CgalPoint> points;
  std::vector<BoundedFace> faces;
  std::vector<CgalVector> normals;
  std::ifstream in(path);
  bool ok = false;
  try {
    ok = CGAL::IO::read_OFF(
        in, points, faces,
        CGAL::parameters::verbose(false).vertex_normal_output_iterator(std::back_inserter(normals)));
  } catch (const Error& e) {  // a face beyond kMaxFaceVertices
    throw file_error(e.code(), path, e.what());
  } catch (const std::exception& e) {  // a CGAL assertion (a 4OFF vertex with w = 0), a failed allocation
    throw file_error(ErrorCode::Io, path, std::string("not a readable OFF file: ") + e.what());
  }
  if (!ok) throw file_error(ErrorCode::Io, path, "not a readable OFF file (a vertex or face line is missing or malformed)");
  Soup soup = soup_of(points, faces);
  if (!normals.empty() && normals.size() == points.size()) soup.normals = rows_of(normals);
  return soup;
}

std::optional<Soup> read_obj(const std::string& path) {
  std::vector<CgalPoint> points;
  std::vector<std::vector<std::int64_t>> faces;
  std::ifstream in(path);
  try {
    if (!CGAL::IO::read_OBJ(in, points, faces, CGAL::parameters::verbose(false))) return std::nullopt;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  for (const std::vector<std::int64_t>& f : faces)
    if (f.size() < 3) return std::nullopt;
  return soup_of(points, faces);
}

Soup read_stl(const std::string& path, std::uint64_t max_points) {
  std::vector<CgalPoint> points;
  std::vector<std::array<std::size_t, 3>> triangles;
  // CGAL reads a short file that is no ASCII STL as a binary one of no triangles, and says it succeeded.
  bool ok = false;
  try {
    ok = CGAL::IO::read_STL(path, points, triangles, CGAL::parameters::verbose(false));
  } catch (const std::exception& e) {
    throw file_error(ErrorCode::Io, path, std::string("not a readable STL file: ") + e.what());
  }
  if (!ok || triangles.empty()) {
    throw file_error(ErrorCode::Io, path, "not a readable STL file (a facet is missing or malformed, or there is none)");
  }
  if (max_points > 0 && points.size() > max_points) {
    throw file_error(ErrorCode::TooLarge, path,
                     std::to_string(points.size()) + " vertices, beyond the limit of " + std::to_string(max_points) + " points");
  }
  return soup_of(points, triangles);
}

}  // namespace surfeledit::mesh_files
