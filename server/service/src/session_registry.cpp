#include "surfeledit/service/session_registry.hpp"

#include <algorithm>

namespace surfeledit::service {

namespace {

constexpr std::size_t kMaxNameLength = 256;  // bytes
constexpr std::size_t kMaxInvites = 64;      // tokens per session (the oldest is dropped first)

void validate_name(const std::string& name) {
  if (name.empty()) throw Error(ErrorCode::InvalidArgument, "session", "a session name is required");
  if (name.size() > kMaxNameLength) {
    throw Error(ErrorCode::InvalidArgument, "session",
                "name of " + std::to_string(name.size()) + " bytes is longer than " + std::to_string(kMaxNameLength));
  }
}

// One message for "does not exist" and "not yours": a refusal tells nothing about other clients' sessions.
Error no_such_session(const std::string& name) {
  return Error(ErrorCode::NotFound, "session", "no session named '" + name + "'");
}

}  // namespace

const Role* SessionEntry::role_of(const std::string& client) const {
  auto it = members.find(client);
  return it == members.end() ? nullptr : &it->second;
}

SessionEntry& SessionRegistry::open(const std::string& name, const std::string& client) {
  validate_name(name);
  auto it = sessions_.find(name);
  if (it == sessions_.end()) {
    SessionEntry entry;
    entry.session = std::make_unique<EditSession>(name, params_);
    entry.owner = client;
    entry.members[client] = Role::Owner;
    it = sessions_.emplace(name, std::move(entry)).first;
  } else if (!it->second.role_of(client)) {
    throw Error(ErrorCode::Conflict, "session",
                "the name '" + name + "' is taken; choose another, or join the session with an invitation token");
  }
  it->second.clients.insert(client);
  it->second.orphaned_since.reset();
  return it->second;
}

SessionEntry& SessionRegistry::restored(const std::string& name) {
  validate_name(name);
  if (sessions_.count(name)) throw Error(ErrorCode::InvalidArgument, "snapshot", "session '" + name + "' saved twice");
  SessionEntry entry;
  entry.session = std::make_unique<EditSession>(name, params_);
  return sessions_.emplace(name, std::move(entry)).first->second;
}

SessionEntry& SessionRegistry::join(const std::string& name, const std::string& client, const std::string& token,
                                    std::optional<Role> granted) {
  validate_name(name);
  auto it = sessions_.find(name);
  if (it == sessions_.end()) throw no_such_session(name);
  SessionEntry& entry = it->second;
  const Role* member = entry.role_of(client);
  auto invite = token.empty() ? entry.invites.end() : entry.invites.find(token);
  if (!member && invite == entry.invites.end() && !granted) throw no_such_session(name);
  std::optional<Role> role;
  if (member) role = *member;
  if (invite != entry.invites.end()) role = role ? std::max(*role, invite->second) : invite->second;
  if (granted) role = role ? std::max(*role, *granted) : *granted;
  entry.members[client] = *role;
  entry.clients.insert(client);
  entry.orphaned_since.reset();
  return entry;
}

SessionEntry& SessionRegistry::attached(const std::string& name, const std::string& client) {
  auto it = sessions_.find(name);
  if (it == sessions_.end() || !it->second.clients.count(client)) {
    throw Error(ErrorCode::Conflict, "session",
                "client '" + client + "' has no open session named '" + name + "'; open or join it first");
  }
  return it->second;
}

bool SessionRegistry::close(const std::string& name, const std::string& client) {
  SessionEntry& entry = attached(name, client);
  entry.clients.erase(client);
  if (!entry.clients.empty()) return false;
  sessions_.erase(name);
  return true;
}

bool SessionRegistry::leave(const std::string& name, const std::string& client) {
  SessionEntry& entry = attached(name, client);
  entry.clients.erase(client);
  return entry.clients.empty();
}

void SessionRegistry::drop(const std::string& name) { sessions_.erase(name); }

std::string SessionRegistry::invite(SessionEntry& entry, Role role, std::string token) {
  if (entry.invites.size() >= kMaxInvites) entry.invites.erase(entry.invites.begin());
  if (token.empty()) token = new_token();
  entry.invites[token] = role;
  return token;
}

SessionEntry* SessionRegistry::find(const std::string& name) {
  auto it = sessions_.find(name);
  return it == sessions_.end() ? nullptr : &it->second;
}

const SessionEntry* SessionRegistry::find(const std::string& name) const {
  auto it = sessions_.find(name);
  return it == sessions_.end() ? nullptr : &it->second;
}

SessionEntry* SessionRegistry::find_for(const std::string& name, const std::string& client) {
  SessionEntry* entry = find(name);
  return entry && entry->role_of(client) ? entry : nullptr;
}

std::vector<std::string> SessionRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(sessions_.size());
  for (const auto& kv : sessions_) out.push_back(kv.first);
  return out;
}

std::vector<std::string> SessionRegistry::names_for(const std::string& client) const {
  std::vector<std::string> out;
  for (const auto& kv : sessions_) {
    if (kv.second.role_of(client)) out.push_back(kv.first);
  }
  return out;
}

std::vector<std::string> SessionRegistry::attached_to(const std::string& client) const {
  std::vector<std::string> out;
  for (const auto& kv : sessions_) {
    if (kv.second.clients.count(client)) out.push_back(kv.first);
  }
  return out;
}

void SessionRegistry::forget_member(const std::string& client) {
  for (auto& kv : sessions_) {
    kv.second.members.erase(client);
    kv.second.activity.erase(client);
  }
}

}  // namespace surfeledit::service
