#include "surfeledit/service/access.hpp"

#include <array>
#include <cctype>
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

namespace {
constexpr const char* kRequestPartitionPrefix = "surfeledit.req.";

bool valid_user(const std::string& user) {
  if (user.empty() || user.size() > 64) return false;
  for (char ch : user) {
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_')) return false;
  }
  return true;
}
}  // namespace

Grant parse_grant(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("grant '" + text + "': expected USER=ROLE[:SESSION]");
  Grant g;
  g.user = text.substr(0, eq);
  const std::string rest = text.substr(eq + 1);
  const auto colon = rest.find(':');
  const std::string role = rest.substr(0, colon);
  if (colon != std::string::npos) g.session = rest.substr(colon + 1);
  if (!valid_user(g.user)) throw std::invalid_argument("grant '" + text + "': user must be 1..64 letters, digits, - or _");
  const auto r = invitable_role(role);
  if (!r) throw std::invalid_argument("grant '" + text + "': role must be editor or viewer");
  g.role = *r;
  if (colon != std::string::npos && (g.session.empty() || g.session.size() > 256)) {
    throw std::invalid_argument("grant '" + text + "': session must be 1..256 characters");
  }
  return g;
}

std::string request_partition(const std::string& user) { return kRequestPartitionPrefix + user; }

std::string request_partition_user(const std::string& partition) {
  const std::string prefix = kRequestPartitionPrefix;
  if (partition.size() <= prefix.size() || partition.compare(0, prefix.size(), prefix) != 0) return {};
  std::string user = partition.substr(prefix.size());
  return valid_user(user) ? user : std::string();
}

std::optional<Role> granted_role(const std::vector<Grant>& grants, const std::string& subject,
                                 const std::string& session) {
  if (subject.empty()) return std::nullopt;
  std::optional<Role> best;
  for (const Grant& g : grants) {
    if (g.user != subject || (!g.session.empty() && g.session != session)) continue;
    if (!best || g.role > *best) best = g.role;
  }
  return best;
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
