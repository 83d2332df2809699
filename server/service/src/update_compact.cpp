#include "surfeledit/service/update_compact.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace surfeledit::service {

namespace {

static_assert(sizeof(float) == 4 && sizeof(std::int16_t) == 2, "the wire's blob element sizes");

bool little_endian() {
  const std::uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// Writes the little-endian bytes of `v` at `out`.
template <typename T>
void put(std::uint8_t* out, T v) {
  std::memcpy(out, &v, sizeof(T));
  if (!little_endian()) std::reverse(out, out + sizeof(T));
}

double sign_not_zero(double x) { return x < 0.0 ? -1.0 : 1.0; }

std::int16_t snorm16(double x) {
  return static_cast<std::int16_t>(std::lround(std::clamp(x, -1.0, 1.0) * 32767.0));
}

}  // namespace

std::array<std::int16_t, 2> octahedral_encode(const double n[3]) {
  const double l1 = std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]);
  if (!(l1 > 0.0) || !std::isfinite(l1)) return {0, 0};  // not a direction: (0, 0) decodes to +z
  double u = n[0] / l1, v = n[1] / l1;
  if (n[2] < 0.0) {  // the lower half folds over the square's diagonals
    const double fu = (1.0 - std::abs(v)) * sign_not_zero(u);
    const double fv = (1.0 - std::abs(u)) * sign_not_zero(v);
    u = fu;
    v = fv;
  }
  return {snorm16(u), snorm16(v)};
}

std::array<double, 3> octahedral_decode(const std::array<std::int16_t, 2>& uv) {
  double x = uv[0] / 32767.0, y = uv[1] / 32767.0;
  const double z = 1.0 - std::abs(x) - std::abs(y);
  if (z < 0.0) {
    const double fx = (1.0 - std::abs(y)) * sign_not_zero(x);
    const double fy = (1.0 - std::abs(x)) * sign_not_zero(y);
    x = fx;
    y = fy;
  }
  const double len = std::sqrt(x * x + y * y + z * z);
  return {x / len, y / len, z / len};
}

CompactSurfels encode_compact(const PreparedUpdate& u, std::size_t begin, std::size_t count) {
  if (begin + count > u.surfels()) throw std::out_of_range("compact encoding beyond the update's surfels");
  CompactSurfels c;
  if (count == 0) return c;
  const double* p = u.positions.data() + 3 * begin;
  for (int a = 0; a < 3; ++a) {
    double lo = p[a], hi = p[a];
    for (std::size_t k = 1; k < count; ++k) {
      lo = std::min(lo, p[3 * k + a]);
      hi = std::max(hi, p[3 * k + a]);
    }
    c.origin[static_cast<std::size_t>(a)] = lo + 0.5 * (hi - lo);
  }
  c.positions.resize(count * 3 * sizeof(float));
  c.normals.resize(count * 2 * sizeof(std::int16_t));
  c.radii.resize(count * sizeof(float));
  const double* n = u.normals.data() + 3 * begin;
  for (std::size_t k = 0; k < count; ++k) {
    for (std::size_t a = 0; a < 3; ++a)
      put(c.positions.data() + (3 * k + a) * sizeof(float), static_cast<float>(p[3 * k + a] - c.origin[a]));
    const std::array<std::int16_t, 2> uv = octahedral_encode(n + 3 * k);
    put(c.normals.data() + 2 * k * sizeof(std::int16_t), uv[0]);
    put(c.normals.data() + (2 * k + 1) * sizeof(std::int16_t), uv[1]);
    put(c.radii.data() + k * sizeof(float), static_cast<float>(u.radii[begin + k]));
  }
  return c;
}

}  // namespace surfeledit::service
