#include "surfeledit/service/session_registry.hpp"

namespace surfeledit::service {

namespace {

constexpr std::size_t kMaxNameLength = 256;  // bytes

void validate_name(const std::string& name) {
  if (name.empty()) throw Error(ErrorCode::InvalidArgument, "session", "a session name is required");
  if (name.size() > kMaxNameLength) {
    throw Error(ErrorCode::InvalidArgument, "session",
                "name of " + std::to_string(name.size()) + " bytes is longer than " + std::to_string(kMaxNameLength));
  }
}

}  // namespace

SessionEntry& SessionRegistry::open(const std::string& name, const std::string& client) {
  validate_name(name);
  auto it = sessions_.find(name);
  if (it == sessions_.end()) {
    SessionEntry entry;
    entry.session = std::make_unique<EditSession>(name, params_);
    it = sessions_.emplace(name, std::move(entry)).first;
  }
  it->second.clients.insert(client);
  return it->second;
}

SessionEntry& SessionRegistry::join(const std::string& name, const std::string& client) {
  validate_name(name);
  auto it = sessions_.find(name);
  if (it == sessions_.end()) throw Error(ErrorCode::NotFound, "session", "no session named '" + name + "'");
  it->second.clients.insert(client);
  return it->second;
}

SessionEntry& SessionRegistry::attached(const std::string& name, const std::string& client) {
  auto it = sessions_.find(name);
  if (it == sessions_.end()) {
    throw Error(ErrorCode::Conflict, "session", "no session named '" + name + "' is open; open or join it first");
  }
  if (!it->second.clients.count(client)) {
    throw Error(ErrorCode::Conflict, "session",
                "client '" + client + "' has not opened or joined session '" + name + "'");
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

SessionEntry* SessionRegistry::find(const std::string& name) {
  auto it = sessions_.find(name);
  return it == sessions_.end() ? nullptr : &it->second;
}

const SessionEntry* SessionRegistry::find(const std::string& name) const {
  auto it = sessions_.find(name);
  return it == sessions_.end() ? nullptr : &it->second;
}

std::vector<std::string> SessionRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(sessions_.size());
  for (const auto& kv : sessions_) out.push_back(kv.first);
  return out;
}

}  // namespace surfeledit::service
