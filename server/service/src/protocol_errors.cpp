#include "surfeledit/service/protocol_errors.hpp"

namespace surfeledit::service {

std::string message_of(const Error& e) {
  const std::string& f = e.field();
  std::string message = e.what();
  if (!f.empty() && message.compare(0, f.size() + 2, f + ": ") == 0) message.erase(0, f.size() + 2);
  return message;
}

void rethrow_prefixed(const Error& e, const std::string& prefix) {
  const std::string& f = e.field();
  if (f == prefix || f.rfind(prefix + ".", 0) == 0) throw e;
  throw Error(e.code(), f.empty() ? prefix : prefix + "." + f, message_of(e));
}

Status status_of(ErrorCode code) { return static_cast<Status>(static_cast<std::uint32_t>(code)); }

}  // namespace surfeledit::service
