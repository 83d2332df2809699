// Who may do what in a session: roles, invitation tokens and the refusal a role check throws.
// Sessions are private to their opener (the owner); others join with a token the owner made by
// OP_INVITE, in the role the invitation names (PROTOCOL.md, "Identity and access").
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

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

// A role granted to an authenticated subject (DDS Security on; `--grant USER=ROLE[:SESSION]`):
// requests from a writer in the partition "surfeledit.req.<user>" (which only that user's
// identity may write in, by its permissions) may join `session`, or every session, in `role`
// without a token (PROTOCOL.md, "Security").
struct Grant {
  std::string user;     // the subject: the certificate's CN, as in the request partition
  Role role = Role::Viewer;  // "editor" or "viewer" (never owner)
  std::string session;  // the session it applies to; empty: every session
};

// Parses "USER=ROLE" or "USER=ROLE:SESSION" (USER: letters, digits, '-', '_'; ROLE: editor or viewer).
// Throws std::invalid_argument naming the text.
Grant parse_grant(const std::string& text);

// The request partition of an authenticated user, "surfeledit.req.<user>"; request_partition_user()
// is its inverse (empty when `partition` is not one).
std::string request_partition(const std::string& user);
std::string request_partition_user(const std::string& partition);

// The role `grants` give `subject` in `session` (the strongest that applies); nullopt: none, or no subject.
std::optional<Role> granted_role(const std::vector<Grant>& grants, const std::string& subject,
                                 const std::string& session);

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
