// Checks of a model file's header before any reader allocates (docs/hardening.md, "Files"): the counts
// a PLY or PCD header announces must fit in the bytes the file actually has, and stay within a point
// limit. Reads at most the first kMaxHeaderBytes of the file, so a huge file of garbage (or a sparse
// file of zeros) fails at once with bounded memory.
#pragma once

#include <cstdint>
#include <string>

namespace surfeledit::model_headers {

constexpr std::uint64_t kMaxHeaderBytes = 64 * 1024;
// binary_compressed PCD: the decompressed data may be at most this many times the file's data bytes.
constexpr std::uint64_t kMaxPcdCompression = 128;

// What a header announces.
struct Announced {
  std::uint64_t points = 0;  // vertices (PLY) / points (PCD) / data lines (XYZ, PWN)
  int columns = 0;           // XYZ, PWN: numbers per data line, 3 (x y z) or 6 (x y z nx ny nz); else 0
};

// Whether `ext` (lower case, with its dot) names a text point set: ".xyz" or ".pwn", a point per line, no header.
inline bool text_point_extension(const std::string& ext) { return ext == ".xyz" || ext == ".pwn"; }

// `ext` is ".ply", ".pcd", ".obj", ".off", ".stl", ".xyz" or ".pwn" (lower case). Throws Error(Io, "path") naming the
// file when the header is missing or malformed or announces more data than the file holds, Error(TooLarge, "path")
// when it announces more than `max_points` points (0: no limit). OBJ: only that the start is text. OFF: ASCII
// only, its counts against the file's size (6 bytes per vertex, 4 per face at least). STL: binary when its size is
// what the triangle count announces (every coordinate finite), else ASCII ("solid" first, no NUL). XYZ and PWN
// (text, a point per line, no header): the whole file is read once, line by line (bounded memory): every line that
// is neither empty nor a '#' comment holds the same number of values, 3 or 6, separated by blanks or commas
// (Error(InvalidArgument, "path") naming the first line that does not); every line, comments too, counts against
// `max_points` (the reader allocates for each).
Announced check(const std::string& path, const std::string& ext, std::uint64_t max_points);

}  // namespace surfeledit::model_headers
