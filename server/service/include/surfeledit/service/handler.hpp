// The request handler: validates and serves one Command at a time (the caller serialises
// calls), keeping sessions, uploads and the idempotence cache. No DDS I/O happens here:
// the caller decodes the request (decode.hpp's decode), writes the returned reply and
// publishes the returned update events. Each op is served by one function of the op table
// (handler_ops.hpp, in src/); this header names project types only.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "surfeledit/core/session_snapshot_view.hpp"
#include "surfeledit/core/surfel_model.hpp"
#include "surfeledit/service/access.hpp"
#include "surfeledit/service/command.hpp"
#include "surfeledit/service/reply.hpp"
#include "surfeledit/service/update.hpp"

namespace surfeledit {
class SnapshotReader;
}  // namespace surfeledit

namespace surfeledit::service {

struct HandlerConfig {
  std::uint64_t max_chunk_surfels = 65536;       // per LoadChunk / StatePage / Update sample
  std::uint64_t max_model_surfels = 20'000'000;  // per model
  int threads = 0;                               // per-session worker threads; 0 = all cores
  std::string data_root;                         // OP_LOAD_FILE reads only below it; empty: file loading off
  std::uint64_t max_file_bytes = std::uint64_t(1) << 30;  // largest file OP_LOAD_FILE reads
  // Identity, leases and memory bounds (PROTOCOL.md, "Identity and access", "Leases").
  std::uint64_t max_client_upload_bytes = std::uint64_t(1200) << 20;  // one client's unfinished uploads
  std::uint64_t max_upload_bytes = std::uint64_t(4096) << 20;         // all unfinished uploads
  std::uint64_t max_reply_cache_bytes = std::uint64_t(64) << 20;      // replies kept for repeats
  std::chrono::milliseconds client_lease{2000};  // a client whose writer is gone this long is detached
  // A session whose last client was detached by its lease (not one closed by its last client) is kept
  // this long, and a detached client's memberships too, so that a restarted client finds them.
  std::chrono::milliseconds session_grace{30000};
  // Roles granted to authenticated subjects (access.hpp, Grant); used only for requests with a subject.
  std::vector<Grant> grants;
};

struct HandlerState;

// One change the passing of time made (Handler::expire_leases): not a request, so the journal records it.
struct Expiry {
  enum class Kind : std::uint8_t {
    Lease = 0,   // the client `name` was detached: its lease ran out
    Grace = 1,   // the session `name` was dropped: no client came back within the grace period
    Forget = 2,  // the client `name` did not come back within the grace period: its memberships are forgotten
  };
  Kind kind = Kind::Lease;
  std::string name;  // client id (Lease, Forget) or session name (Grace)
};

class Handler {
 public:
  explicit Handler(HandlerConfig config);
  ~Handler();
  Handler(const Handler&) = delete;
  Handler& operator=(const Handler&) = delete;

  // Serves one request and returns its reply (the stored one for a repeated request id).
  // Appends the changes to publish to `updates`. Never throws for bad input: every
  // failure becomes an error reply, and a failed request changes nothing. Returns nullptr (no
  // reply now) for an OP_LOAD_FILE whose file is being read, or a repeat of one (the reply comes
  // later from finish_loads()), and when the command's client id is bound to another sender (a
  // reply would carry the victim's id and reach the victim, not the sender).
  std::shared_ptr<const Reply> handle(const Command& command, std::vector<UpdateEvent>& updates);
  // Commits the file loads that finished off the request thread (in the order they finished) and
  // returns their replies; appends their updates. Each OP_LOAD_FILE gets exactly one reply.
  std::vector<std::shared_ptr<const Reply>> finish_loads(std::vector<UpdateEvent>& updates);
  // Called from a loading thread when a load finished (wakes the request thread); set before serving.
  void set_on_load_done(std::function<void()> on_done);

  // Leases (client_ops.cpp). The request writer `sender` lost its liveliness or was unmatched /
  // is alive again; clients bound to it are detached once it stayed gone for config().client_lease.
  void writer_lost(std::uint64_t sender);
  void writer_alive(std::uint64_t sender);
  // Detaches every client whose lease ran out: releases its tools, detaches it from its sessions
  // (a "presence" update "expired" each; a session left without clients is kept for the grace
  // period), drops its uploads and cached replies and forgets its id (its memberships are kept for
  // the grace period). Drops the sessions whose grace period ran out without a client coming back
  // (a "close" update each) and forgets the memberships of detached clients that did not come back.
  // Appends the updates to `updates`; returns the ids detached.
  // `applied` (when given) gets every change made, in order, for the journal.
  std::vector<std::string> expire_leases(std::vector<UpdateEvent>& updates, std::vector<Expiry>* applied = nullptr);
  // Detaches one client as its lease would (expire_leases), drops a session whose grace period ran
  // out, forgets the memberships of a client that did not come back: the journal replays what
  // expire_leases did with it.
  void apply_expiry(const Expiry& expiry, std::vector<UpdateEvent>& updates);
  // Time until the next lease or grace period can run out (nullopt: none is running).
  std::optional<std::chrono::milliseconds> next_lease_check() const;

  // The journal (journal.hpp). `on_stored` is called on the request thread each time a reply is
  // stored for repeats of its request id (a request served, not a repeat: handle(), finish_loads()),
  // before the reply is returned; empty: no call. It must not throw.
  void set_on_stored(std::function<void(const Reply&)> on_stored);
  // After recovery: a lease of `rejoin` starts for every client attached to a session, so one that
  // never comes back is detached like one whose writer was lost (a request from it stops the lease).
  void start_recovered_leases(std::chrono::milliseconds rejoin);
  // Stores a reply for repeats of its request id as handle() does (replay of a refused request).
  void remember(const Reply& reply);
  // The token the next OP_INVITE hands out instead of a fresh random one (replay); once.
  void set_next_token(std::string token);

  // Journal snapshots (handler_snapshot.cpp; docs/journal.md). not_snapshottable(): why the state
  // kept between requests cannot be saved now ("" when it can): a session that is not snapshottable
  // (EditSession::not_snapshottable), an unfinished upload, a file load in progress. save(): appends
  // that state (sessions with their members, roles, invitations, activity and grace, the clients away,
  // the replies kept for repeats as the CDR of the IDL Reply) to `parts`, whose concatenation is the
  // snapshot (the sessions' core snapshots are parts of their own: not copied); Internal when not snapshottable.
  // restore(): replaces it by a saved one, read and checked whole before anything changes (a corrupt
  // one throws and changes nothing); times are kept as durations before the save. Clients are bound to
  // no writer afterwards, as after a replay (start_recovered_leases).
  struct SnapshotBlock {
    std::string why;    // empty: the state can be saved
    bool soon = false;  // an unfinished upload or a running file load: ends by itself, worth trying again soon
  };
  SnapshotBlock not_snapshottable() const;
  // A snapshot taken at one point and encoded later, on another thread while requests go on (the
  // journal's writer thread): the service's own state encoded at the point, each session's as a view
  // (EditSession::snapshot_view: its history images shared, not copied). encode() appends exactly the
  // parts save() would have appended at the point; save(parts) is snapshot().encode(parts).
  struct Snapshot {
    std::vector<std::string> heads;           // the bytes before each session's core snapshot (but its size)
    std::vector<SessionSnapshotView> sessions;
    std::string tail;                         // the clients away and the replies kept
    void encode(std::vector<std::string>& parts) const;
    std::size_t copied_bytes() const;         // encoded at the point
    std::size_t shared_images() const;        // history images shared
  };
  Snapshot snapshot() const;
  void save(std::vector<std::string>& parts) const;
  void restore(SnapshotReader& in);

  // The model an update event refers to (nullptr when its session is gone or has none).
  const SurfelModel* model_of(const std::string& session);
  const HandlerConfig& config() const;
  // An event carrying what changed in the session since version `since` (ids changed or inserted,
  // removed ids; the whole model when it was replaced since), at its current version; cause and
  // step are left for the caller. nullopt when the session is gone.
  std::optional<UpdateEvent> changes_event(const std::string& session, std::uint64_t since) const;

 private:
  std::unique_ptr<HandlerState> state_;
};

// Name of an op for logs ("OP_DEFORM"), or "OP_<number>" for a value outside the op table.
std::string op_name(Op op);
// Whether the op table has a handler for `op` (every value of proto Op has one).
bool has_handler(Op op);

}  // namespace surfeledit::service
