// Polygon meshes as surfels, and the mesh files read with CGAL (OFF, STL) for model_io.cpp. CGAL's types stay in
// mesh_files.cpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "surfeledit/core/surfel_model.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::mesh_files {

// A polygon soup: vertices (#V by 3) and faces, each a list of vertex rows (a polygon of more than three is a fan).
struct Soup {
  Points vertices;
  std::vector<std::vector<std::int64_t>> faces;
  Points normals;  // #V by 3 where the file states vertex normals (NOFF), else empty
};

// One surfel per vertex some face refers to, its normal the normalised sum of the incident triangles' unnormalised
// normals (area-weighted); a vertex whose sum is zero is dropped. Throws Error(InvalidArgument, "path"), naming
// `path`, for a non-finite vertex, a face referring to a vertex the soup does not have, or no usable vertex.
SurfelArrays surfels_of(const Soup& soup, const std::string& path);

// An ASCII OFF file whose header model_headers::check accepted: a mesh, or a point set when it has no face.
// Coordinates as float64. Throws Error(Io, "path")
// when CGAL's reader fails, Error(InvalidArgument, "path") for a face of more than kMaxFaceVertices vertices.
Soup read_off(const std::string& path);

// An OBJ mesh in float64 (PCL's OBJ reader keeps float32, which loses a model 1e6 from the origin), or nothing when
// CGAL's reader does not take the file (no face, a statement it does not know, such as `l`) or gives a face of
// fewer than three vertices (it reads only blank-separated indices): the caller then reads it with PCL.
std::optional<Soup> read_obj(const std::string& path);

// An STL file, ASCII or binary (float32), whose size model_headers::check accepted; CGAL merges the triangles'
// corners at equal coordinates into one vertex. Throws Error(Io, "path") when CGAL's reader fails,
// Error(TooLarge, "path") for more than `max_points` vertices (0: no limit).
Soup read_stl(const std::string& path, std::uint64_t max_points);

// The most vertices a face of an OFF file may have: the reader allocates a face's count before reading it.
constexpr std::size_t kMaxFaceVertices = 1 << 16;

}  // namespace surfeledit::mesh_files
