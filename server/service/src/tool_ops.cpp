// Handler functions of the tool ops (issue 11 §1): RELEASE frees the caller's tool in the session (its
// regions, detector and lock). Leaving the session (CLOSE_SESSION, a lease that expired) releases it too
// (release_tool, presence_ops.cpp).
#include "handler_ops.hpp"

namespace surfeledit::service {

void serve_release(OpContext& c) {
  // A tool without regions holds no lock: nothing changes, the version stays (no update).
  release_tool(*c.entry, c.command.session, c.command.client_id, c.updates);
}

}  // namespace surfeledit::service
