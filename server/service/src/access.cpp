#include "surfeledit/service/access.hpp"

#include <array>
#include <random>

#include "surfeledit/service/command.hpp"

namespace surfeledit::service {

const char* role_name(Role role) {
  switch (role) {
    case Role::Viewer: return "viewer";
    case Role::Editor: return "editor";
    case Role::Owner: return "owner";
  }
  return "unknown";
}

std::optional<Role> invitable_role(const std::string& name) {
  if (name == "editor") return Role::Editor;
  if (name == "viewer") return Role::Viewer;
  return std::nullopt;
}

Role required_role(std::uint32_t op) {
  switch (static_cast<Op>(op)) {
    case Op::Info:
    case Op::OpenSession:
    case Op::JoinSession:
    case Op::CloseSession:
    case Op::GetState:
    case Op::History:
    case Op::Curves:
    case Op::Peers: return Role::Viewer;
    case Op::Invite: return Role::Owner;
    default: return Role::Editor;  // every other op changes the session (or an upload into it)
  }
}

std::string new_token() {
  static thread_local std::random_device device;  // the OS's entropy source
  static const char* kHex = "0123456789abcdef";
  std::string token;
  token.reserve(32);
  for (int word = 0; word < 4; ++word) {
    const std::uint32_t bits = device();
    for (int nibble = 0; nibble < 8; ++nibble) token.push_back(kHex[(bits >> (4 * nibble)) & 0xf]);
  }
  return token;
}

}  // namespace surfeledit::service
