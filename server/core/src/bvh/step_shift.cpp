// The step's largest displacement (step_shift.hpp).
#include "step_shift.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace surfeledit::detail {

StepShift step_shift(const CollisionScene& scene, const Points& previous, const IndexList& deformable,
                     std::vector<double>& prev_radius) {
  const double* p = scene.positions.data();
  const double* q = previous.data();
  const double* rad = scene.radii.data();
  double t2a = 0.0, t2b = 0.0, grow = 0.0;
  const std::size_t n = deformable.size();
  auto d2 = [&](Index r) {
    const double* x = p + 3 * static_cast<std::ptrdiff_t>(r);
    const double* y = q + 3 * static_cast<std::ptrdiff_t>(r);
    const double a = x[0] - y[0], b = x[1] - y[1], c = x[2] - y[2];
    return a * a + b * b + c * c;
  };
  std::size_t k = 0;
  for (; k + 1 < n; k += 2) {  // two chains of maxima
    t2a = std::max(t2a, d2(deformable[k]));
    t2b = std::max(t2b, d2(deformable[k + 1]));
  }
  if (k < n) t2a = std::max(t2a, d2(deformable[k]));
  for (k = 0; k < n; ++k) {
    const double r = rad[deformable[k]];
    if (r != prev_radius[k]) {
      grow = std::max(grow, r - prev_radius[k]);
      prev_radius[k] = r;
    }
  }
  StepShift s;
  s.reach = std::sqrt(std::max(t2a, t2b)) * (1.0 + 1e-12);
  s.shift = (s.reach + grow) * (1.0 + 1e-12);
  return s;
}

}  // namespace surfeledit::detail
