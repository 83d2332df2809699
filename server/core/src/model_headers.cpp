#include "model_headers.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "file_error.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::model_headers {

namespace {

[[noreturn]] void bad(const std::string& path, const std::string& what) { throw file_error(ErrorCode::Io, path, what); }

// The file's size and its first kMaxHeaderBytes bytes.
struct Head {
  std::uint64_t size = 0;
  std::string bytes;
};

Head read_head(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot be opened");
  Head h;
  in.seekg(0, std::ios::end);
  h.size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(0);
  h.bytes.resize(static_cast<std::size_t>(std::min<std::uint64_t>(h.size, kMaxHeaderBytes)));
  in.read(h.bytes.data(), static_cast<std::streamsize>(h.bytes.size()));
  h.bytes.resize(static_cast<std::size_t>(in.gcount()));
  return h;
}

// Header lines up to and including the one starting with `last` (e.g. "end_header"); `end` is set to
// the byte offset just after it. Fails when it is not within the head.
std::vector<std::string> header_lines(const std::string& path, const Head& h, const std::string& last,
                                      std::uint64_t& end) {
  std::vector<std::string> lines;
  std::size_t pos = 0;
  while (pos < h.bytes.size()) {
    const std::size_t nl = h.bytes.find('\n', pos);
    if (nl == std::string::npos) break;
    std::string line = h.bytes.substr(pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = nl + 1;
    lines.push_back(line);
    if (line.compare(0, last.size(), last) == 0) {
      end = pos;
      return lines;
    }
  }
  bad(path, "no '" + last + "' line within the first " + std::to_string(kMaxHeaderBytes) + " bytes");
}

std::uint64_t parse_count(const std::string& path, const std::string& text, const std::string& what) {
  if (text.empty() || text.size() > 19 || !std::all_of(text.begin(), text.end(), ::isdigit)) {
    bad(path, what + " '" + text + "' is not a count");
  }
  return std::stoull(text);
}

// a * b, or UINT64_MAX when it overflows (then it exceeds any file).
std::uint64_t times(std::uint64_t a, std::uint64_t b) {
  if (a != 0 && b > UINT64_MAX / a) return UINT64_MAX;
  return a * b;
}

std::uint64_t plus(std::uint64_t a, std::uint64_t b) { return b > UINT64_MAX - a ? UINT64_MAX : a + b; }

void check_points(const std::string& path, std::uint64_t points, std::uint64_t max_points) {
  if (max_points > 0 && points > max_points) {
    throw file_error(ErrorCode::TooLarge, path,
                     "the header announces " + std::to_string(points) + " points, beyond the limit of " +
                         std::to_string(max_points));
  }
}

void check_fits(const std::string& path, std::uint64_t need, std::uint64_t have, const std::string& what) {
  if (need > have) {
    bad(path, "the header announces " + what + " (at least " + std::to_string(need) + " bytes) but the file has " +
                  std::to_string(have) + " bytes after it");
  }
}

int ply_scalar_size(const std::string& type) {
  static const std::map<std::string, int> sizes = {
      {"char", 1},  {"uchar", 1},  {"int8", 1},  {"uint8", 1},   {"short", 2},   {"ushort", 2},
      {"int16", 2}, {"uint16", 2}, {"int", 4},   {"uint", 4},    {"int32", 4},   {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

Announced check_ply(const std::string& path, const Head& h, std::uint64_t max_points) {
  if (h.bytes.compare(0, 4, "ply\n") != 0 && h.bytes.compare(0, 5, "ply\r\n") != 0) bad(path, "not a PLY file");
  std::uint64_t end = 0;
  const std::vector<std::string> lines = header_lines(path, h, "end_header", end);
  bool ascii = false, has_format = false;
  struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::uint64_t min_bytes = 0;  // the least one element can take in the file
  };
  std::vector<Element> elements;
  for (std::size_t i = 1; i + 1 < lines.size(); ++i) {
    std::istringstream in(lines[i]);
    std::string word;
    in >> word;
    if (word == "format") {
      std::string format;
      in >> format;
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        bad(path, "unknown PLY format '" + format + "'");
      }
      ascii = format == "ascii";
      has_format = true;
    } else if (word == "element") {
      Element e;
      std::string count;
      in >> e.name >> count;
      e.count = parse_count(path, count, "element " + e.name + " count");
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) bad(path, "a property before any element");
      std::string type;
      in >> type;
      std::uint64_t bytes = 0;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type;
        if (!ply_scalar_size(count_type) || !ply_scalar_size(item_type)) bad(path, "unknown PLY list type");
        bytes = ascii ? 2 : static_cast<std::uint64_t>(ply_scalar_size(count_type));  // an empty list
      } else {
        if (!ply_scalar_size(type)) bad(path, "unknown PLY property type '" + type + "'");
        bytes = ascii ? 2 : static_cast<std::uint64_t>(ply_scalar_size(type));  // ascii: a digit and a separator
      }
      elements.back().min_bytes += bytes;
    } else if (word != "comment" && word != "obj_info" && !word.empty()) {
      bad(path, "unexpected PLY header line '" + lines[i].substr(0, 80) + "'");
    }
  }
  if (!has_format) bad(path, "no PLY format line");
  Announced a;
  std::uint64_t need = 0;
  for (const Element& e : elements) {
    if (e.name == "vertex") a.points = e.count;
    // An element without properties still takes a line (ascii) or is refused beyond the file's size.
    need = plus(need, times(e.count, std::max<std::uint64_t>(e.min_bytes, 1)));
  }
  check_points(path, a.points, max_points);
  check_fits(path, need, h.size - end, "its elements");
  return a;
}

Announced check_pcd(const std::string& path, const Head& h, std::uint64_t max_points) {
  std::uint64_t end = 0;
  const std::vector<std::string> lines = header_lines(path, h, "DATA", end);
  std::vector<std::uint64_t> sizes, counts;
  std::uint64_t width = 0, height = 1, points = 0, fields = 0;
  bool has_width = false, has_points = false;
  std::string data;
  for (const std::string& line : lines) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string key, value;
    in >> key;
    std::vector<std::string> values;
    while (in >> value) values.push_back(value);
    if (key == "FIELDS") {
      fields = values.size();
    } else if (key == "SIZE" || key == "COUNT") {
      std::vector<std::uint64_t>& out = key == "SIZE" ? sizes : counts;
      for (const std::string& v : values) out.push_back(parse_count(path, v, key));
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      if (values.size() != 1) bad(path, key + " needs one value");
      const std::uint64_t v = parse_count(path, values[0], key);
      if (key == "WIDTH") width = v, has_width = true;
      else if (key == "HEIGHT") height = v;
      else points = v, has_points = true;
    } else if (key == "DATA") {
      data = values.empty() ? "" : values[0];
    }
  }
  if (fields == 0 || sizes.size() != fields || (!counts.empty() && counts.size() != fields) || !has_width) {
    bad(path, "not a readable PCD file (FIELDS, SIZE, COUNT and WIDTH missing or inconsistent)");
  }
  std::uint64_t step = 0, values_per_point = 0;
  for (std::size_t i = 0; i < fields; ++i) {
    const std::uint64_t count = counts.empty() ? 1 : counts[i];
    if (sizes[i] == 0 || sizes[i] > 8 || count > (1u << 20)) bad(path, "a PCD field of size 0 or beyond 8 bytes, or count beyond 2^20");
    step += sizes[i] * count;
    values_per_point += count;
  }
  Announced a;
  a.points = times(width, height);
  if (has_points && points != a.points) {
    bad(path, "POINTS " + std::to_string(points) + " differs from WIDTH x HEIGHT = " + std::to_string(a.points));
  }
  check_points(path, a.points, max_points);
  const std::uint64_t have = h.size - end;
  if (data == "binary") {
    check_fits(path, times(a.points, step), have, std::to_string(a.points) + " binary points");
  } else if (data == "ascii") {
    check_fits(path, times(a.points, times(values_per_point, 2)), have, std::to_string(a.points) + " text points");
  } else if (data == "binary_compressed") {
    check_fits(path, times(a.points, step), times(have, kMaxPcdCompression),
               std::to_string(a.points) + " compressed points (decompressing to over " +
                   std::to_string(kMaxPcdCompression) + " times the data)");
  } else {
    bad(path, "unknown PCD DATA '" + data + "'");
  }
  return a;
}

// A text point set: counts its data lines and their values (docs/hardening.md, "Files").
Announced check_text_points(const std::string& path, std::uint64_t max_points) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot be opened");
  Announced a;
  std::string line;
  std::uint64_t number = 0;
  auto refuse = [&](const std::string& what) {
    throw file_error(ErrorCode::InvalidArgument, path, "line " + std::to_string(number) + " " + what);
  };
  while (std::getline(in, line)) {
    // Every line counts: PCL's reader allocates a point for each before it skips comments and empty ones.
    ++number;
    if (max_points > 0 && number > max_points) {
      throw file_error(ErrorCode::TooLarge, path, "more than " + std::to_string(max_points) +
                                                   " lines, beyond the limit of " + std::to_string(max_points) + " points");
    }
    if (line.find('\0') != std::string::npos) bad(path, "not a text file (line " + std::to_string(number) + " holds NUL bytes)");
    int values = 0;
    bool in_value = false;
    for (const char c : line) {
      const bool separator = c == ' ' || c == '\t' || c == ',' || c == '\r';
      if (!separator && !in_value) ++values;
      in_value = !separator;
    }
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (values == 0 || line[first] == '#') continue;  // empty, or a comment
    if (a.columns == 0) {
      if (values != 3 && values != 6) refuse("holds " + std::to_string(values) + " values, not 3 (x y z) or 6 (x y z nx ny nz)");
      a.columns = values;
    } else if (values != a.columns) {
      refuse("holds " + std::to_string(values) + " values where the first point's line held " + std::to_string(a.columns));
    }
    ++a.points;
  }
  return a;
}

// ASCII OFF: "[ST][C][N][4]OFF", then the vertex, face and edge counts ('#' comments anywhere). CGAL's reader sizes
// its arrays by the counts before it reads a line, so each vertex must have its 6 bytes ("0 0 0\n") and each face
// its 4 ("1 0\n") in the file.
Announced check_off(const std::string& path, const Head& h, std::uint64_t max_points) {
  std::vector<std::string> tokens;  // the keyword and the three counts, comments skipped
  bool binary = false;
  std::uint64_t end = 0;            // the offset after the last token read (the edge count)
  std::size_t pos = 0;
  while (pos < h.bytes.size() && tokens.size() < 4) {
    const char c = h.bytes[pos];
    if (c == '#') {
      const std::size_t nl = h.bytes.find('\n', pos);
      pos = nl == std::string::npos ? h.bytes.size() : nl + 1;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++pos;
    } else {
      const std::size_t stop = h.bytes.find_first_of(" \t\r\n#", pos);
      tokens.push_back(h.bytes.substr(pos, stop == std::string::npos ? std::string::npos : stop - pos));
      pos = stop == std::string::npos ? h.bytes.size() : stop;
      if (tokens.size() == 2 && tokens[1] == "BINARY") {
        binary = true;
        tokens.pop_back();
      }
      end = pos;
    }
  }
  if (h.bytes.find('\0') != std::string::npos) bad(path, "not a text OFF file (holds NUL bytes)");
  const std::string magic = tokens.empty() ? std::string() : tokens[0];
  const std::size_t prefix = magic.size() >= 3 ? magic.size() - 3 : 0;
  if (magic.size() < 3 || magic.compare(prefix, 3, "OFF") != 0 ||
      magic.find_first_not_of("STCN4n") < prefix) {
    bad(path, "not an OFF file (no OFF keyword first)");
  }
  if (magic.find('n') < prefix) bad(path, "'" + magic + "': an OFF file of another dimension than 3 is not supported");
  if (binary) bad(path, "binary OFF is not supported (save it as ASCII OFF)");
  if (tokens.size() < 4) bad(path, "no vertex, face and edge counts within the first " + std::to_string(kMaxHeaderBytes) + " bytes");
  const std::uint64_t vertices = parse_count(path, tokens[1], "the vertex count");
  const std::uint64_t faces = parse_count(path, tokens[2], "the face count");
  parse_count(path, tokens[3], "the edge count");
  check_points(path, vertices, max_points);
  const std::uint64_t need = plus(times(vertices, 6), times(faces, 4));
  check_fits(path, need > 0 ? need - 1 : 0, h.size - end,
             std::to_string(vertices) + " vertices and " + std::to_string(faces) + " faces");
  Announced a;
  a.points = vertices;
  return a;
}

// STL: binary when the size is exactly 84 bytes plus 50 per triangle the header's count announces (then every
// vertex coordinate must be finite: CGAL's reader merges equal corners with an ordered map, which a NaN breaks);
// otherwise ASCII, which must start with "solid". Both readers allocate as they read, bounded by the file's size.
Announced check_stl(const std::string& path, const Head& h, std::uint64_t max_points) {
  (void)max_points;  // the distinct vertices are counted after reading (mesh_files::read_stl)
  const bool solid = h.bytes.compare(0, 5, "solid") == 0;
  std::uint32_t triangles = 0;
  if (h.bytes.size() >= 84) std::memcpy(&triangles, h.bytes.data() + 80, 4);  // little-endian, as x86 and ARM are
  if (h.size >= 84 && h.size == plus(84, times(triangles, 50))) {
    std::ifstream in(path, std::ios::binary);
    in.seekg(84);
    char facet[50];
    for (std::uint32_t t = 0; t < triangles; ++t) {
      if (!in.read(facet, sizeof facet)) bad(path, "cannot read triangle " + std::to_string(t));
      for (int k = 3; k < 12; ++k) {
        float x = 0.0f;
        std::memcpy(&x, facet + 4 * k, 4);
        if (!std::isfinite(x)) bad(path, "triangle " + std::to_string(t) + " has a non-finite vertex coordinate");
      }
    }
    return {};
  }
  if (!solid) {
    bad(path, "not an STL file: neither ASCII (\"solid\" first) nor binary (84 bytes + 50 per triangle: " +
                  std::to_string(plus(84, times(triangles, 50))) + " bytes for the " + std::to_string(triangles) +
                  " the header announces; the file has " + std::to_string(h.size) + ")");
  }
  if (h.bytes.find('\0') != std::string::npos) bad(path, "not a text STL file (holds NUL bytes)");
  return {};
}

}  // namespace

Announced check(const std::string& path, const std::string& ext, std::uint64_t max_points) {
  if (text_point_extension(ext)) return check_text_points(path, max_points);
  const Head h = read_head(path);
  if (ext == ".ply") return check_ply(path, h, max_points);
  if (ext == ".pcd") return check_pcd(path, h, max_points);
  if (ext == ".off") return check_off(path, h, max_points);
  if (ext == ".stl") return check_stl(path, h, max_points);
  if (h.bytes.find('\0') != std::string::npos) bad(path, "not a text OBJ file (holds NUL bytes)");
  return {};
}

}  // namespace surfeledit::model_headers
