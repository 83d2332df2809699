// The handler's state in a journal snapshot (docs/journal.md "Snapshots"; Handler::save / restore):
// every session (EditSession::save) with what the service keeps about it, the clients away, and the
// replies kept for repeated request ids, each as the CDR of the IDL Reply (no per-op code).
#include <chrono>
#include <map>
#include <optional>

#include "handler_ops.hpp"
#include "journal_records.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "surfeledit/service/decode.hpp"
#include "surfeledit/service/journal.hpp"
#include "surfeledit/service/sample_views.hpp"

namespace surfeledit::service {

namespace {

constexpr std::uint32_t kServiceMagic = 0x56524553;  // "SERV"
constexpr std::uint32_t kServiceFormat = 1;          // this layout

using Clock = std::chrono::steady_clock;

// A time point as the nanoseconds before `now` it lies (negative: after), and back.
std::int64_t age_of(Clock::time_point t, Clock::time_point now) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(now - t).count();
}
Clock::time_point from_age(std::int64_t age, Clock::time_point now) { return now - std::chrono::nanoseconds(age); }

Role read_role(SnapshotReader& in, const char* what) {
  const std::uint8_t r = in.u8(what);
  if (r > static_cast<std::uint8_t>(Role::Owner)) in.fail(what, "unknown role " + std::to_string(r));
  return static_cast<Role>(r);
}

// The service's fields of a session; its EditSession follows (save_session).
void save_entry(SnapshotWriter& w, const std::string& name, const SessionEntry& e, Clock::time_point now) {
  w.str(name);
  w.str(e.owner);
  w.u64(e.steps);
  w.u64(e.clients.size());
  for (const std::string& c : e.clients) w.str(c);
  w.u64(e.members.size());
  for (const auto& [client, role] : e.members) {
    w.str(client);
    w.u8(static_cast<std::uint8_t>(role));
  }
  w.u64(e.invites.size());
  for (const auto& [token, role] : e.invites) {
    w.str(token);
    w.u8(static_cast<std::uint8_t>(role));
  }
  w.u64(e.activity.size());
  for (const auto& [client, a] : e.activity) {
    w.str(client);
    w.str(a.last_op);
    w.u64(a.last_version);
    w.i64(age_of(a.last_request, now));
  }
  w.boolean(e.orphaned_since.has_value());
  w.i64(e.orphaned_since ? age_of(*e.orphaned_since, now) : 0);
}

void restore_entry(SnapshotReader& in, SessionRegistry& sessions, Clock::time_point now) {
  SessionEntry& e = sessions.restored(in.str("session name"));
  e.owner = in.str("owner");
  e.steps = in.u64("steps");
  for (std::size_t n = in.count("clients", 8); n > 0; --n) e.clients.insert(in.str("client"));
  for (std::size_t n = in.count("members", 9); n > 0; --n) {
    std::string client = in.str("member");
    e.members[client] = read_role(in, "member role");
  }
  for (std::size_t n = in.count("invites", 9); n > 0; --n) {
    std::string token = in.str("invite");
    e.invites[token] = read_role(in, "invite role");
  }
  for (std::size_t n = in.count("activity", 32); n > 0; --n) {
    PeerActivity& a = e.activity[in.str("activity client")];
    a.last_op = in.str("last op");
    a.last_version = in.u64("last version");
    a.last_request = from_age(in.i64("last request"), now);
  }
  const bool orphaned = in.boolean("orphaned");
  const std::int64_t orphaned_age = in.i64("orphaned since");
  if (orphaned) e.orphaned_since = from_age(orphaned_age, now);
  const std::string bytes = in.str("session state");
  SnapshotReader session(bytes);
  e.session->restore(session);
}

// A stored reply as it was sent: the CDR of its IDL sample.
std::string reply_cdr(const Reply& reply) {
  std::vector<std::uint8_t> cdr = reply.wire;
  if (cdr.empty()) {
    const ReplyView view(reply);
    cdr = journal::sample_cdr(view.get(), surfeledit_proto_Reply_desc);
  }
  return std::string(cdr.begin(), cdr.end());
}

// A reply restored from its CDR: the members the cache and the journal read, and the whole as `wire`.
std::shared_ptr<const Reply> reply_from_cdr(const std::string& bytes) {
  auto reply = std::make_shared<Reply>();
  reply->wire.assign(bytes.begin(), bytes.end());
  const journal::ReplySample sample(reply->wire);
  const surfeledit_proto_Reply& r = sample.get();
  reply->client_id = str(r.client_id);
  reply->request_id = r.request_id;
  reply->request_op = static_cast<std::uint32_t>(r.request_op);
  reply->status = static_cast<Status>(r.status);
  reply->field = str(r.field);
  reply->message = str(r.message);
  reply->version = r.version;
  reply->token = str(r.token);
  return reply;
}

}  // namespace

Handler::SnapshotBlock Handler::not_snapshottable() const {
  const HandlerState& s = *state_;
  if (s.uploads.size() > 0) return {std::to_string(s.uploads.size()) + " upload(s) unfinished", true};
  if (!s.loads.idle()) return {"a file load is in progress", true};
  for (const auto& [name, entry] : s.sessions.all()) {
    const std::string why = entry.session->not_snapshottable();
    if (!why.empty()) return {"session '" + name + "': " + why, false};
  }
  return {};
}

Handler::Snapshot Handler::snapshot() const {
  const std::string why = not_snapshottable().why;
  if (!why.empty()) throw Error(ErrorCode::Internal, "snapshot", "the service state cannot be saved: " + why);
  const HandlerState& s = *state_;
  const Clock::time_point now = Clock::now();
  Snapshot snap;
  SnapshotWriter w;
  w.u32(kServiceMagic);
  w.u32(kServiceFormat);
  w.u64(s.sessions.size());
  for (const auto& [name, entry] : s.sessions.all()) {
    save_entry(w, name, entry, now);
    // The session's bytes follow as a string of the stream (u64 size, bytes: the core's reader checks it
    // reads them to the end); encode() writes both.
    snap.heads.push_back(w.take());
    w = SnapshotWriter();
    snap.sessions.push_back(entry.session->snapshot_view());
  }
  w.u64(s.away.size());
  for (const auto& [client, since] : s.away) {
    w.str(client);
    w.i64(age_of(since, now));
  }
  std::vector<std::pair<std::string, std::size_t>> replies;
  s.cache.for_each_oldest_first([&](const Reply& r, std::size_t bytes) { replies.emplace_back(reply_cdr(r), bytes); });
  w.u64(replies.size());
  for (const auto& [cdr, bytes] : replies) {
    w.u64(bytes);
    w.str(cdr);
  }
  snap.tail = w.take();
  return snap;
}

void Handler::Snapshot::encode(std::vector<std::string>& parts) const {
  for (std::size_t k = 0; k < sessions.size(); ++k) {
    // Each session's bytes are a part of their own, not copied into the stream's.
    SnapshotWriter session;
    sessions[k].encode(session);
    SnapshotWriter head;
    head.raw(heads[k].data(), heads[k].size());
    head.u64(session.bytes().size());
    parts.push_back(head.take());
    parts.push_back(session.take());
  }
  parts.push_back(tail);
}

std::size_t Handler::Snapshot::copied_bytes() const {
  std::size_t n = tail.size();
  for (const std::string& h : heads) n += h.size();
  for (const SessionSnapshotView& v : sessions) n += v.copied_bytes();
  return n;
}

std::size_t Handler::Snapshot::shared_images() const {
  std::size_t n = 0;
  for (const SessionSnapshotView& v : sessions) n += v.shared_images();
  return n;
}

void Handler::save(std::vector<std::string>& parts) const { snapshot().encode(parts); }

void Handler::restore(SnapshotReader& in) {
  HandlerState& s = *state_;
  const Clock::time_point now = Clock::now();
  if (in.u32("service magic") != kServiceMagic) in.fail("service magic", "not a service snapshot");
  const std::uint32_t format = in.u32("service format");
  if (format != kServiceFormat) in.fail("service format", "unknown service snapshot format " + std::to_string(format));
  // Everything is read into new objects first: a failure leaves the handler as it was.
  SessionRegistry sessions(SessionParams{s.config.threads});
  for (std::size_t n = in.count("sessions", 64); n > 0; --n) restore_entry(in, sessions, now);
  std::map<std::string, LeaseClock::time_point> away;
  for (std::size_t n = in.count("away", 16); n > 0; --n) {
    std::string client = in.str("away client");
    away[client] = from_age(in.i64("away since"), now);
  }
  std::vector<std::pair<std::shared_ptr<const Reply>, std::size_t>> replies;
  for (std::size_t n = in.count("replies", 16); n > 0; --n) {
    const std::uint64_t bytes = in.u64("reply bytes");
    try {
      replies.emplace_back(reply_from_cdr(in.str("reply")), static_cast<std::size_t>(bytes));
    } catch (const JournalError& e) {
      in.fail("reply", e.what());
    }
  }
  in.expect_end();
  RequestCache cache(s.cache.limits());
  for (auto& [reply, bytes] : replies) cache.put(std::move(reply), bytes);
  s.sessions = std::move(sessions);
  s.away = std::move(away);
  s.cache = std::move(cache);
}

}  // namespace surfeledit::service
