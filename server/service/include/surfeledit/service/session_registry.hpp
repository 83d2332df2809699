// Sessions by name, the clients attached to each and who may see them: a session is private to
// the client that opened it (its owner); others become members with a token the owner made
// (invite) and then open, join, read or edit it as their role allows (access.hpp). A session is
// dropped when its last attached client closes it or is detached.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/service/access.hpp"

namespace surfeledit::service {

// What a client last did in one session (OP_PEERS).
struct PeerActivity {
  std::string last_op;                                 // its last op that changed the version ("" before any)
  std::uint64_t last_version = 0;                      // the version that op produced
  std::chrono::steady_clock::time_point last_request;  // its last request served in this session
};

struct SessionEntry {
  std::unique_ptr<EditSession> session;
  std::set<std::string> clients;         // attached client ids
  std::uint64_t steps = 0;               // deformation steps applied so far
  std::string owner;                     // the client that opened it
  std::map<std::string, Role> members;   // client id -> role (the owner included); kept while attached or not
  std::map<std::string, Role> invites;   // token -> role it grants (valid until the session is dropped)
  std::map<std::string, PeerActivity> activity;  // member client id -> what it last did here
  // Its last client was detached (lease) at this time: it is kept for the grace period, then dropped;
  // nullopt while a client is attached.
  std::optional<std::chrono::steady_clock::time_point> orphaned_since;

  // The client's role; nullptr when it is not a member.
  const Role* role_of(const std::string& client) const;
};

class SessionRegistry {
 public:
  explicit SessionRegistry(SessionParams params = {}) : params_(params) {}

  // Creates the session (the client becomes its owner) or attaches a member to it. Throws
  // InvalidArgument (field "session") on an empty or overlong name, Conflict (field "session")
  // when the name belongs to a session the client is not a member of (join it with a token).
  SessionEntry& open(const std::string& name, const std::string& client);
  // Attaches a member, or makes the client a member with the role a valid `token` grants, or the
  // role `granted` to its authenticated subject (--grant; the stronger of those that apply). A
  // session that does not exist and a non-member without a valid token or grant get the same NotFound.
  SessionEntry& join(const std::string& name, const std::string& client, const std::string& token,
                     std::optional<Role> granted = std::nullopt);
  // The session the client is attached to; throws Conflict (field "session") otherwise, with the
  // same message whether the session exists or not.
  SessionEntry& attached(const std::string& name, const std::string& client);
  // Detaches the client (Conflict if not attached); returns true when that dropped the session. The
  // caller releases the client's tool first (release_tool, handler_ops.hpp).
  bool close(const std::string& name, const std::string& client);
  // Detaches the client without dropping the session (Conflict if not attached); returns true when
  // no client is attached any more (the caller keeps it for the grace period, then drop()s it).
  bool leave(const std::string& name, const std::string& client);
  // A session restored from a journal snapshot: a new entry `name` with an empty EditSession of this
  // registry's params, for the caller to fill (InvalidArgument when the name is taken).
  SessionEntry& restored(const std::string& name);
  // Drops the session (nothing when there is none).
  void drop(const std::string& name);
  // A token granting `role` in the session (the caller checked the inviter's role): `token` when
  // given (the journal's replay hands out the token recorded), a fresh random one otherwise.
  std::string invite(SessionEntry& entry, Role role, std::string token = {});

  SessionEntry* find(const std::string& name);
  const SessionEntry* find(const std::string& name) const;
  // The session when `client` is a member of it (nullptr otherwise, also when it does not exist).
  SessionEntry* find_for(const std::string& name, const std::string& client);
  // Names, sorted: all of them, and those `client` is a member of.
  std::vector<std::string> names() const;
  std::vector<std::string> names_for(const std::string& client) const;
  // Sessions the client is attached to, sorted.
  std::vector<std::string> attached_to(const std::string& client) const;
  // Forgets the client's memberships (it was detached for good); attachments are closed by the caller first.
  void forget_member(const std::string& client);
  // Every session, for the lease and grace checks.
  std::map<std::string, SessionEntry>& all() { return sessions_; }
  const std::map<std::string, SessionEntry>& all() const { return sessions_; }
  std::size_t size() const { return sessions_.size(); }

 private:
  SessionParams params_;
  std::map<std::string, SessionEntry> sessions_;
};

}  // namespace surfeledit::service
