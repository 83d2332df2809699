#include "surfeledit/core/simplify/params.hpp"

#include <cmath>

namespace surfeledit {

void validate(const SimplifyParams& params) {
  if (params.method != SimplifyMethod::None && params.method != SimplifyMethod::RegionGrowing &&
      params.method != SimplifyMethod::Hierarchical) {
    throw Error(ErrorCode::InvalidArgument, "simplify", "unknown simplification method");
  }
  if (params.cluster_size < 1) {
    throw Error(ErrorCode::InvalidArgument, "cluster_size",
                "cluster_size must be >= 1, got " + std::to_string(params.cluster_size));
  }
  if (!std::isfinite(params.max_variation) || params.max_variation < 0.0 || params.max_variation > 1.0) {
    throw Error(ErrorCode::InvalidArgument, "max_variation",
                "max_variation must be in [0, 1], got " + std::to_string(params.max_variation));
  }
  if (!std::isfinite(params.member_margin) || params.member_margin < 0.0) {
    throw Error(ErrorCode::InvalidArgument, "member_margin",
                "member_margin must be finite and >= 0, got " + std::to_string(params.member_margin));
  }
  if (params.threads < 0) {
    throw Error(ErrorCode::InvalidArgument, "threads", "threads must be >= 0, got " + std::to_string(params.threads));
  }
}

}  // namespace surfeledit
