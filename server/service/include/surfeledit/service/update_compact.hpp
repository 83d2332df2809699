// The compact encoding of an update's surfels (proto/PROTOCOL.md "Updates, compact"; issue 14): what a
// watcher that chose it receives instead of doubles. Per part of an update:
//  - positions: float32 offsets from the part's bounding-box centre `origin` (kept as doubles); per
//    coordinate the error is at most 2^-24 times the offset's magnitude (round to nearest), i.e. at most
//    2^-25 times the part's box extent along that axis, plus the doubles' own rounding (2^-52 |x|);
//  - normals: octahedral coordinates (u, v) of the unit normal as int16 (times 32767); the decoded
//    normal is within kOctahedralMaxAngle radians of the encoded one (largest measured over 10^6 random
//    normals and the octahedron's edges: 6.4e-5; tests/service/test_update_compact.cpp);
//  - radii: float32 (relative error at most 2^-24).
// Ids, removed ids, colliding ids, clip lines and every other field are sent as in the full encoding.
// Blobs are little-endian, as the wire documents them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "surfeledit/service/update.hpp"

namespace surfeledit::service {

// Largest angle (radians) between a unit normal and its octahedral int16 encoding decoded.
constexpr double kOctahedralMaxAngle = 1e-4;

// The octahedral int16 coordinates of the unit vector n (any non-zero length is accepted: it is
// projected onto the octahedron first).
std::array<std::int16_t, 2> octahedral_encode(const double n[3]);
// The unit vector of octahedral coordinates uv.
std::array<double, 3> octahedral_decode(const std::array<std::int16_t, 2>& uv);

// The compact geometry of surfels [begin, begin + count) of an update.
struct CompactSurfels {
  std::array<double, 3> origin{};       // the part's bounding-box centre (zero for an empty part)
  std::vector<std::uint8_t> positions;  // count*3 float32, little endian: offsets from origin
  std::vector<std::uint8_t> normals;    // count*2 int16, little endian: octahedral coordinates
  std::vector<std::uint8_t> radii;      // count float32, little endian
};

CompactSurfels encode_compact(const PreparedUpdate& update, std::size_t begin, std::size_t count);

}  // namespace surfeledit::service
