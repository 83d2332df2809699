// Sessions by name and the clients attached to each; a session is dropped when its last
// client closes it.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "surfeledit/core/edit_session.hpp"

namespace surfeledit::service {

struct SessionEntry {
  std::unique_ptr<EditSession> session;
  std::set<std::string> clients;  // attached client ids
  std::uint64_t steps = 0;        // deformation steps applied so far
};

class SessionRegistry {
 public:
  explicit SessionRegistry(SessionParams params = {}) : params_(params) {}

  // Creates the session (or attaches to it) and attaches the client. Throws
  // InvalidArgument (field "session") on an empty or overlong name.
  SessionEntry& open(const std::string& name, const std::string& client);
  // Attaches the client to an existing session; throws NotFound otherwise.
  SessionEntry& join(const std::string& name, const std::string& client);
  // The session the client is attached to; throws Conflict (field "session") otherwise.
  SessionEntry& attached(const std::string& name, const std::string& client);
  // Detaches the client (Conflict if not attached); returns true when that dropped the session.
  bool close(const std::string& name, const std::string& client);

  SessionEntry* find(const std::string& name);
  const SessionEntry* find(const std::string& name) const;
  // Names, sorted.
  std::vector<std::string> names() const;
  std::size_t size() const { return sessions_.size(); }

 private:
  SessionParams params_;
  std::map<std::string, SessionEntry> sessions_;
};

}  // namespace surfeledit::service
