#include "surfeledit/core/model_io.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/PolygonMesh.h>
#include <pcl/io/ascii_io.h>
#include <pcl/io/obj_io.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/console/print.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <optional>

#include "file_error.hpp"
#include "mesh_files.hpp"
#include "model_headers.hpp"
#include "point_normals.hpp"

namespace surfeledit {
namespace {

namespace fs = std::filesystem;

std::string extension_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

const pcl::PCLPointField* find_field(const pcl::PCLPointCloud2& c, const std::string& name) {
  for (const auto& f : c.fields)
    if (f.name == name) return &f;
  return nullptr;
}

double read_scalar(const std::uint8_t* p, std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: { std::int8_t v; std::memcpy(&v, p, 1); return v; }
    case pcl::PCLPointField::UINT8: { std::uint8_t v; std::memcpy(&v, p, 1); return v; }
    case pcl::PCLPointField::INT16: { std::int16_t v; std::memcpy(&v, p, 2); return v; }
    case pcl::PCLPointField::UINT16: { std::uint16_t v; std::memcpy(&v, p, 2); return v; }
    case pcl::PCLPointField::INT32: { std::int32_t v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::UINT32: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::FLOAT32: { float v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::FLOAT64: { double v; std::memcpy(&v, p, 8); return v; }
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

std::size_t scalar_size(std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: case pcl::PCLPointField::UINT8: return 1;
    case pcl::PCLPointField::INT16: case pcl::PCLPointField::UINT16: return 2;
    case pcl::PCLPointField::FLOAT64: return 8;
    default: return 4;
  }
}

// What a reader returned is consistent: every point's bytes are there and `f` lies inside a point. A
// reader that miscounted (or a file that contradicts its header) is refused instead of read past its end.
void check_layout(const std::string& path, const pcl::PCLPointCloud2& c, const pcl::PCLPointField& f) {
  const std::uint64_t n = std::uint64_t(c.width) * c.height;
  if (std::uint64_t(f.offset) + scalar_size(f.datatype) > c.point_step || c.data.size() / std::max<std::uint32_t>(c.point_step, 1) < n) {
    throw file_error(ErrorCode::Io, path, "the data does not match the header (field '" + f.name + "')");
  }
}

// Reads named scalar fields into an n by k matrix; false if any is missing.
bool read_fields(const std::string& path, const pcl::PCLPointCloud2& c, const std::vector<std::string>& names,
                 Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& out) {
  std::vector<const pcl::PCLPointField*> fields;
  for (const auto& n : names) {
    const auto* f = find_field(c, n);
    if (!f) return false;
    check_layout(path, c, *f);
    fields.push_back(f);
  }
  const std::size_t n = static_cast<std::size_t>(c.width) * c.height;
  out.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(names.size()));
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* base = c.data.data() + i * c.point_step;
    for (std::size_t k = 0; k < fields.size(); ++k)
      out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) =
          read_scalar(base + fields[k]->offset, fields[k]->datatype);
  }
  return true;
}

// Packed "rgb"/"rgba" (float or uint32 bit pattern) -> #P by 3 colours; empty if absent.
Colors read_colors(const std::string& path, const pcl::PCLPointCloud2& c) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m;
  if (read_fields(path, c, {"red", "green", "blue"}, m))  // separate channels (as PLY keeps them)
    return m.cwiseMax(0.0).cwiseMin(255.0).cast<std::uint8_t>();
  const pcl::PCLPointField* f = find_field(c, "rgb");
  if (!f) f = find_field(c, "rgba");
  if (!f || (f->datatype != pcl::PCLPointField::FLOAT32 && f->datatype != pcl::PCLPointField::UINT32)) return {};
  check_layout(path, c, *f);
  const std::size_t n = static_cast<std::size_t>(c.width) * c.height;
  Colors out(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t v;
    std::memcpy(&v, c.data.data() + i * c.point_step + f->offset, 4);
    out(i, 0) = (v >> 16) & 0xff;
    out(i, 1) = (v >> 8) & 0xff;
    out(i, 2) = v & 0xff;
  }
  return out;
}

// Extra vertex properties of the clip lines (float64, exact round trip).
const std::vector<std::string> kClipPointFields = {"clip_px", "clip_py", "clip_pz"};
const std::vector<std::string> kClipDirFields = {"clip_dx", "clip_dy", "clip_dz"};

// A point set's surfels: `positions` (#P by 3, at least one, finite) and `normals`, the file's (#P by 3) or, when
// the file has none (empty), estimated ones.
SurfelArrays point_set(Points positions, Points normals, const std::string& path, const LoadParams& params) {
  if (positions.rows() == 0) throw file_error(ErrorCode::InvalidArgument, path, "the file holds no points");
  checked_in_file(path, [&] { require_finite(positions, "positions"); });
  SurfelArrays a;
  a.normals = normals.rows() == positions.rows() ? std::move(normals) : estimate_normals(positions, params.normal_k, path);
  a.positions = std::move(positions);
  return a;
}

SurfelArrays from_cloud(const pcl::PCLPointCloud2& c, const std::string& path, const LoadParams& params) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m;
  if (!read_fields(path, c, {"x", "y", "z"}, m)) throw file_error(ErrorCode::Io, path, "no x, y, z fields");
  Points positions = m;
  Points normals;  // the normal fields are read only for a non-empty set, which point_set refuses first
  if (positions.rows() > 0 &&
      (read_fields(path, c, {"normal_x", "normal_y", "normal_z"}, m) || read_fields(path, c, {"nx", "ny", "nz"}, m))) {
    normals = m;
  }
  SurfelArrays a = point_set(std::move(positions), std::move(normals), path, params);
  if (read_fields(path, c, {"radius"}, m)) a.radii = m.col(0);
  a.colors = read_colors(path, c);
  // Clip lines of a merge's crease (extra vertex properties written by save_surfels).
  if (read_fields(path, c, kClipPointFields, m)) {
    a.clip_points = m;
    if (!read_fields(path, c, kClipDirFields, m)) throw file_error(ErrorCode::Io, path, "clip line points without directions");
    a.clip_dirs = m;
  }
  return a;
}

// A PCL mesh (OBJ, PLY with faces) as a soup for mesh_files::surfels_of.
SurfelArrays from_mesh(const pcl::PolygonMesh& mesh, const std::string& path) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m;
  if (!read_fields(path, mesh.cloud, {"x", "y", "z"}, m)) throw file_error(ErrorCode::Io, path, "no vertex coordinates");
  mesh_files::Soup soup;
  soup.vertices = m;
  soup.faces.reserve(mesh.polygons.size());
  for (const pcl::Vertices& f : mesh.polygons) soup.faces.emplace_back(f.vertices.begin(), f.vertices.end());
  return mesh_files::surfels_of(soup, path);
}

// A text point set (.xyz, .pwn) whose lines model_headers::check counted: x y z, or x y z nx ny nz, per line, read by
// PCL's ASCII reader as float64 fields. It skips a line it cannot parse (a value that is not a number) and leaves the
// cloud's width at the file's line count, so both are checked here against the counted data lines.
pcl::PCLPointCloud2 read_text_points(const std::string& path, const model_headers::Announced& announced) {
  if (announced.points == 0) throw file_error(ErrorCode::InvalidArgument, path, "the file holds no points");
  static const char* const kNames[] = {"x", "y", "z", "normal_x", "normal_y", "normal_z"};
  std::vector<pcl::PCLPointField> fields;
  for (int k = 0; k < announced.columns; ++k) {
    pcl::PCLPointField f;
    f.name = kNames[k];
    f.offset = static_cast<std::uint32_t>(8 * k);
    f.datatype = pcl::PCLPointField::FLOAT64;
    f.count = 1;
    fields.push_back(f);
  }
  pcl::ASCIIReader reader;
  reader.setInputFields(fields);
  reader.setSepChars(" \t,\r\n");
  reader.setExtension(fs::path(path).extension().string());  // it compares the name's own spelling
  pcl::PCLPointCloud2 cloud;
  if (reader.read(path, cloud) < 0) throw file_error(ErrorCode::Io, path, "not a readable text point file");
  const std::uint64_t read = cloud.point_step ? cloud.data.size() / cloud.point_step : 0;
  if (read != announced.points) {
    throw file_error(ErrorCode::InvalidArgument, path,
                     std::to_string(announced.points - read) + " of its " + std::to_string(announced.points) +
                         " point lines hold a value that is not a number");
  }
  cloud.width = static_cast<std::uint32_t>(read);
  cloud.height = 1;
  cloud.row_step = cloud.width * cloud.point_step;
  return cloud;
}

}  // namespace

bool loadable_extension(const std::string& ext) {
  return ext == ".ply" || ext == ".pcd" || ext == ".obj" || ext == ".off" || ext == ".stl" ||
         model_headers::text_point_extension(ext);
}

const char* loadable_formats() {
  return "use .ply, .pcd, .obj, .off (ASCII), .stl, or .xyz / .pwn: text, a point per line, x y z [nx ny nz]";
}

SurfelArrays load_surfels(const std::string& path, LoadParams params) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw file_error(ErrorCode::NotFound, path, "no such file");
  if (fs::is_directory(path, ec)) throw file_error(ErrorCode::Io, path, "is a directory");
  if (!fs::is_regular_file(path, ec)) throw file_error(ErrorCode::Io, path, "not a regular file");  // a FIFO would block
  const std::string ext = extension_of(path);
  if (!loadable_extension(ext)) {
    throw file_error(ErrorCode::InvalidArgument, path, "unsupported extension '" + ext + "' (" + loadable_formats() + ")");
  }
  // Counts the header announces against the file's size and the point limit, before any reader allocates.
  const model_headers::Announced announced = model_headers::check(path, ext, params.max_points);
  SurfelArrays a;
  // PCL reports problems on its console; we report them as exceptions instead.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  if (ext == ".obj") {
    // CGAL's reader keeps float64; PCL's (float32) reads what CGAL's does not: points without faces, lines, ...
    if (std::optional<mesh_files::Soup> soup = mesh_files::read_obj(path)) {
      a = mesh_files::surfels_of(*soup, path);
    } else {
      pcl::PolygonMesh mesh;
      if (pcl::io::loadOBJFile(path, mesh) < 0) throw file_error(ErrorCode::Io, path, "not a readable OBJ file");
      a = mesh.polygons.empty() ? from_cloud(mesh.cloud, path, params) : from_mesh(mesh, path);
    }
  } else if (ext == ".ply") {
    pcl::PolygonMesh mesh;
    pcl::PLYReader reader;
    if (reader.read(path, mesh) < 0) throw file_error(ErrorCode::Io, path, "not a readable PLY file");
    a = mesh.polygons.empty() ? from_cloud(mesh.cloud, path, params) : from_mesh(mesh, path);
  } else if (ext == ".pcd") {
    pcl::PCLPointCloud2 cloud;
    pcl::PCDReader reader;
    // PCL 1.13's PCDReader::read crashes on files without a valid header: check it first.
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int pcd_version = 0, data_type = 0;
    unsigned int data_offset = 0;
    if (reader.readHeader(path, cloud, origin, orientation, pcd_version, data_type, data_offset) < 0 ||
        cloud.fields.empty() || cloud.point_step == 0 || std::uint64_t(cloud.width) * cloud.height == 0) {
      throw file_error(ErrorCode::Io, path, "not a readable PCD file (no valid header with fields and points)");
    }
    const std::uint64_t need = std::uint64_t(data_offset) + std::uint64_t(cloud.width) * cloud.height * cloud.point_step;
    if (data_type == 1 && fs::file_size(path, ec) < need) {  // binary: the data must all be there
      throw file_error(ErrorCode::Io, path, "truncated: the header announces " + std::to_string(need) + " bytes, the file has " +
                               std::to_string(fs::file_size(path, ec)));
    }
    cloud = pcl::PCLPointCloud2();
    if (reader.read(path, cloud) < 0) throw file_error(ErrorCode::Io, path, "not a readable PCD file");
    a = from_cloud(cloud, path, params);
  } else if (ext == ".off") {
    mesh_files::Soup soup = mesh_files::read_off(path);
    if (!soup.faces.empty()) {
      a = mesh_files::surfels_of(soup, path);
    } else {  // a point set: its normals from the file (NOFF), else estimated
      a = point_set(std::move(soup.vertices), std::move(soup.normals), path, params);
    }
  } else if (ext == ".stl") {
    a = mesh_files::surfels_of(mesh_files::read_stl(path, params.max_points), path);
  } else if (model_headers::text_point_extension(ext)) {
    a = from_cloud(read_text_points(path, announced), path, params);
  } else {
    throw file_error(ErrorCode::InvalidArgument, path, "unsupported extension '" + ext + "' (" + loadable_formats() + ")");
  }
  checked_in_file(path, [&] { validate_arrays(a); });
  return a;
}

void save_surfels(const std::string& path, const SurfelArrays& a) {
  validate_arrays(a);
  const std::string ext = extension_of(path);
  if (ext != ".ply" && ext != ".pcd") {
    throw file_error(ErrorCode::InvalidArgument, path, "unsupported extension '" + ext + "' (use .ply or .pcd)");
  }
  const Eigen::Index n = a.positions.rows();
  const bool radii = a.radii.size() == n;
  const bool colors = a.colors.rows() == n;
  const bool clips = a.clip_dirs.rows() == n && n > 0;
  // Layout: x y z (float64, full precision), normal_x..z (float32), radius (float32), rgb, clip lines
  // clip_px..pz, clip_dx..dz (float64) when the model has them.
  pcl::PCLPointCloud2 c;
  std::uint32_t offset = 0;
  auto add = [&](const std::string& name, std::uint8_t type, std::uint32_t size) {
    pcl::PCLPointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    c.fields.push_back(f);
    offset += size;
  };
  for (const char* f : {"x", "y", "z"}) add(f, pcl::PCLPointField::FLOAT64, 8);
  for (const char* f : {"normal_x", "normal_y", "normal_z"}) add(f, pcl::PCLPointField::FLOAT32, 4);
  if (radii) add("radius", pcl::PCLPointField::FLOAT32, 4);
  // PLY: three uchar properties. PCL's PLYWriter declares a packed UINT32 "rgb" as three uchar properties
  // but writes all four bytes, so the file contradicts its own header (the old bad_alloc on loading).
  const bool ply = ext == ".ply";
  if (colors && ply)
    for (const char* f : {"red", "green", "blue"}) add(f, pcl::PCLPointField::UINT8, 1);
  if (colors && !ply) add("rgb", pcl::PCLPointField::UINT32, 4);
  if (clips)
    for (const auto* names : {&kClipPointFields, &kClipDirFields})
      for (const std::string& f : *names) add(f, pcl::PCLPointField::FLOAT64, 8);
  c.width = static_cast<std::uint32_t>(n);
  c.height = 1;
  c.point_step = offset;
  c.row_step = offset * c.width;
  c.is_dense = true;
  c.data.resize(static_cast<std::size_t>(c.row_step));
  for (Eigen::Index i = 0; i < n; ++i) {
    std::uint8_t* p = c.data.data() + i * offset;
    for (int k = 0; k < 3; ++k) {
      const double v = a.positions(i, k);
      std::memcpy(p + 8 * k, &v, 8);
    }
    for (int k = 0; k < 3; ++k) {
      const float v = static_cast<float>(a.normals(i, k));
      std::memcpy(p + 24 + 4 * k, &v, 4);
    }
    std::uint32_t o = 36;
    if (radii) {
      const float v = static_cast<float>(a.radii[i]);
      std::memcpy(p + o, &v, 4);
      o += 4;
    }
    if (colors && ply) {
      for (int k = 0; k < 3; ++k) p[o + k] = static_cast<std::uint8_t>(a.colors(i, k));
      o += 3;
    } else if (colors) {
      const std::uint32_t v = (std::uint32_t(a.colors(i, 0)) << 16) | (std::uint32_t(a.colors(i, 1)) << 8) | a.colors(i, 2);
      std::memcpy(p + o, &v, 4);
      o += 4;
    }
    if (clips) {
      for (int k = 0; k < 3; ++k) std::memcpy(p + o + 8 * k, &a.clip_points(i, k), 8);
      for (int k = 0; k < 3; ++k) std::memcpy(p + o + 24 + 8 * k, &a.clip_dirs(i, k), 8);
    }
  }
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  int rc = 0;
  if (ext == ".ply") {
    pcl::PLYWriter w;
    rc = w.writeBinary(path, c);
  } else {
    pcl::PCDWriter w;
    rc = w.writeBinary(path, c);
  }
  if (rc < 0) throw file_error(ErrorCode::Io, path, "could not be written");
}

}  // namespace surfeledit
