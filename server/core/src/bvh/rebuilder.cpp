// Names of the deformable tree's status.
#include "surfeledit/core/bvh/rebuilder.hpp"

namespace surfeledit::bvh {

const char* to_string(BvhStatus status) {
  switch (status) {
    case BvhStatus::Fresh: return "fresh";
    case BvhStatus::Refit: return "refit";
    case BvhStatus::Rebuilding: return "rebuilding";
  }
  return "?";
}

}  // namespace surfeledit::bvh
