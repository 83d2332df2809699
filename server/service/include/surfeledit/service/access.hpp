// Who may do what in a session: roles, invitation tokens and the refusal a role check throws.
// Sessions are private to their opener (the owner); others join with a token the owner made by
// OP_INVITE, in the role the invitation names (PROTOCOL.md, "Identity and access").
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace surfeledit::service {

// A client's role in one session, weakest first.
enum class Role : std::uint8_t {
  Viewer = 0,  // watches and reads (INFO, GET_STATE, HISTORY, CURVES, PEERS); changes nothing
  Editor = 1,  // and changes the session (load, regions, deform, configure, remove, undo, redo, merge)
  Owner = 2,   // and invites others (OP_INVITE); the client that created the session
};

// "viewer" | "editor" | "owner".
const char* role_name(Role role);
// The role an invitation may grant ("editor" or "viewer"); nullopt for anything else.
std::optional<Role> invitable_role(const std::string& name);

// The weakest role an op needs in its session (ops that need no session: Viewer).
// `op` is the protocol op number.
Role required_role(std::uint32_t op);

// A fresh invitation token: 128 random bits as 32 hex digits.
std::string new_token();

// Thrown when the caller's role does not allow the op; the handler answers
// STATUS_PERMISSION_DENIED naming `field` (the session).
class PermissionDenied : public std::runtime_error {
 public:
  PermissionDenied(std::string field, const std::string& message)
      : std::runtime_error(message), field_(std::move(field)) {}
  const std::string& field() const { return field_; }

 private:
  std::string field_;
};

}  // namespace surfeledit::service
