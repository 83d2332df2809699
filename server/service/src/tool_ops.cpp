// Handler functions of the tool ops (issue 11 §1): RELEASE frees the caller's tool in the session (its
// regions, detector and lock). Leaving the session (CLOSE_SESSION, a lease that expired) releases it too
// (SessionRegistry::close).
#include "handler_ops.hpp"

namespace surfeledit::service {

void serve_release(OpContext& c) {
  EditSession& s = *c.entry->session;
  // A tool without regions holds no lock: nothing changes, the version stays (no update).
  if (s.release(c.command.client_id)) c.updates.push_back(make_update_event(c.command.session, s.version(), "release"));
}

}  // namespace surfeledit::service
