// One server per DDS domain. Two servers on one domain would both answer every request (two replies, two
// update streams from two diverging copies of a session), so a server refuses to start where another one
// already serves (PROTOCOL.md, "One server per domain").
//
// How: every server marks its default-partition reply writer with a user-data marker (`ServerMarker`). At
// start, a probe reader on the reply topic (other participants' writers only) looks for such a marker during a
// discovery window; the probe is deleted when the window ends, so a running server receives nothing through it.
// Of two servers that start within one window and discover each other, the later marker (start time, then pid,
// then host) gives way and the earlier one keeps serving. Private to the service library.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "dds_handles.hpp"

namespace surfeledit::service {

// Who a server is, as carried in its reply writer's user data: "surfeledit-server start=<ns> pid=<pid> host=<name>".
struct ServerMarker {
  std::int64_t start_ns = 0;  // wall-clock start time, ns since the Unix epoch
  std::int64_t pid = 0;       // process id
  std::string host;           // host name

  static ServerMarker of_this_process();
  std::string text() const;
  // The marker in `text`, or nothing when it is not a server's marker (any other writer on the topic).
  static std::optional<ServerMarker> parse(const std::string& text);
  // True if this server started before `other` (ties broken by pid, then host): the one that keeps serving.
  bool precedes(const ServerMarker& other) const;
};

class DomainGuard {
 public:
  // Creates the probe reader on `reply_topic` (a participant's own writers are not matched) and opens the
  // discovery window: it ends `window_ns` (nanoseconds) after this call.
  DomainGuard(const dds::Entity& participant, const dds::Entity& reply_topic, ServerMarker self,
              dds_duration_t window_ns);
  // True once the discovery window has ended at `now_ns` (dds_time() scale).
  bool expired(dds_time_t now_ns) const { return now_ns >= deadline_ns_; }
  // Waits until the window ends for another server's reply writer and deletes the probe. Returns the marker
  // of a server this one must give way to (it started earlier), else nothing; a later server found in the
  // window is left to give way itself.
  std::optional<ServerMarker> earlier_server();

 private:
  // The earliest marker among the writers matched now that precedes `self_`.
  std::optional<ServerMarker> scan() const;

  ServerMarker self_;
  dds_time_t deadline_ns_;  // end of the discovery window (dds_time() scale)
  dds::Entity probe_;
  dds::Entity waitset_;
};

}  // namespace surfeledit::service
