// The one message for an unknown enum name (enum_names.hpp).
#include "surfeledit/core/enum_names.hpp"

#include "surfeledit/core/types.hpp"

namespace surfeledit {

void throw_unknown_name(const std::string& field, const std::string& name, const std::string& choices) {
  throw Error(ErrorCode::InvalidArgument, field, "unknown value '" + name + "'; expected one of " + choices);
}

}  // namespace surfeledit
