#include "surfeledit/core/selector.hpp"

#include <cmath>
#include <sstream>

namespace surfeledit {

void validate(const Selector& s, const std::string& field) {
  require_finite(s.center.transpose(), field + ".center");
  if (s.kind == Selector::Kind::Sphere) {
    if (!std::isfinite(s.radius) || s.radius < 0.0) {
      std::ostringstream msg;
      msg << "sphere radius " << s.radius << " must be finite and >= 0";
      throw Error(ErrorCode::InvalidArgument, field + ".radius", msg.str());
    }
  } else if (s.kind == Selector::Kind::Box) {
    require_finite(s.half_extents.transpose(), field + ".half_extents");
    if ((s.half_extents.array() < 0.0).any()) {
      std::ostringstream msg;
      msg << "box half extents (" << s.half_extents.transpose() << ") must be >= 0";
      throw Error(ErrorCode::InvalidArgument, field + ".half_extents", msg.str());
    }
  } else {
    throw Error(ErrorCode::InvalidArgument, field + ".kind", "unknown selector kind");
  }
}

IndexList select_rows(const Points& positions, const Selector& s) {
  IndexList rows;
  const double r2 = s.radius * s.radius;
  for (Eigen::Index i = 0; i < positions.rows(); ++i) {
    const Vec3 d = positions.row(i).transpose() - s.center;
    const bool in = s.kind == Selector::Kind::Sphere
                        ? d.squaredNorm() <= r2
                        : (d.array().abs() <= s.half_extents.array()).all();
    if (in) rows.push_back(static_cast<Index>(i));
  }
  return rows;
}

}  // namespace surfeledit
