// Service: its DDS entities and the request thread (the waitset loop, requests served into replies,
// leases, the journal's group commit). The update path is service_updates.cpp.
#include "surfeledit/service/service.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <string>
#include <vector>

#include "journal_records.hpp"
#include "service_config.hpp"
#include "service_impl.hpp"
#include "surfeledit/service/decode.hpp"
#include "surfeledit/service/log.hpp"
#include "surfeledit/service/sample_views.hpp"

namespace surfeledit::service {

namespace {

// Topic names (PROTOCOL.md).
constexpr const char* kRequestTopic = "surfeledit_request";
constexpr const char* kReplyTopic = "surfeledit_reply";
constexpr const char* kUpdateTopic = "surfeledit_update";
// Watchers that choose the compact encoding read updates in this partition (PROTOCOL.md).
constexpr const char* kCompactUpdatePartition = "surfeledit.update.compact";

// The request reader's partitions: the default one (clients without DDS Security) and every
// authenticated user's "surfeledit.req.<user>" (access.hpp, request_partition).
const std::vector<std::string> kRequestPartitions{"", "surfeledit.req.*"};
// Request writers whose subject is remembered at once (subject_of).
constexpr std::size_t kMaxSubjects = 4096;

// Waitset tags.
constexpr dds_attach_t kRequestsTag = 1;
constexpr dds_attach_t kStopTag = 2;
constexpr dds_attach_t kLoadsTag = 3;
constexpr dds_attach_t kWritersTag = 4;
constexpr dds_attach_t kWatchersTag = 5;  // an update writer matched a new watcher
constexpr dds_attach_t kSnapshotTag = 6;  // the journal's writer thread finished a snapshot file

// Topic types with their XTypes type information (PROTOCOL.md, "Topics and QoS"), so that DDS tools
// (`cyclonedds typeof`, `cyclonedds ls`) can show them. Request has no enum-typed member (op and kinds
// are `long`): the server, a C 0.10.2 reader, judges the Python wheel's Request assignable.
const dds_topic_descriptor_t& kRequestType = surfeledit_proto_Request_desc;
const dds_topic_descriptor_t& kReplyType = surfeledit_proto_Reply_desc;
const dds_topic_descriptor_t& kUpdateType = surfeledit_proto_Update_desc;

// Requests taken per loan.
constexpr std::size_t kTakeBatch = 16;

// Liveliness lease the reply writer offers (automatic: Cyclone asserts it); clients take a reply
// writer that is not alive for this long as a dead server (PROTOCOL.md, "Leases").
constexpr dds_duration_t kServerLiveliness = DDS_MSECS(1000);

}  // namespace

Service::Impl::Impl(const ServiceConfig& c)
    : config(c),
      handler(handler_config(c)),
      domain(dds::make_domain(static_cast<dds_domainid_t>(c.domain))),
      participant(dds::make_participant(static_cast<dds_domainid_t>(c.domain),
                                        c.security.empty() ? std::vector<SecurityProperty>{}
                                                           : security_properties(c.security))),
      qos(dds::protocol_qos()),
      request_topic(dds::make_topic(participant, &kRequestType, kRequestTopic, qos)),
      reply_topic(dds::make_topic(participant, &kReplyType, kReplyTopic, qos)),
      update_topic(dds::make_topic(participant, &kUpdateType, kUpdateTopic, qos)),
      request_subscriber(dds::make_subscriber(participant, dds::Qos().partitions(kRequestPartitions))),
      writer_wake(participant),
      request_reader(make_request_reader()),
      reply_qos(dds::protocol_qos()),
      reply_writer(dds::make_writer(participant, reply_topic,
                                    reply_qos.automatic_liveliness(kServerLiveliness).user_data(marker.text()))),
      client_replies(participant, reply_topic, kServerLiveliness),
      update_writer(dds::make_writer(participant, update_topic, qos)),
      compact_publisher(dds::make_publisher(participant, dds::Qos().partition(kCompactUpdatePartition))),
      compact_update_writer(dds::make_writer(compact_publisher, update_topic, qos)),
      requests(dds::make_read_condition(request_reader)),
      stop_guard(participant),
      loads_guard(participant),
      snapshot_guard(participant),
      waitset(participant),
      publisher(make_publisher(c)) {
  if (c.domain_probe_ms > 0) {  // first: discovery runs while the journal recovers
    try {
      domain_guard.emplace(participant, reply_topic, marker, DDS_MSECS(static_cast<std::int64_t>(c.domain_probe_ms)));
    } catch (const std::runtime_error& e) {  // e.g. DDS Security permissions without surfeledit_reply
      logger()->warn("cannot look for another server on domain {}: {}", c.domain, e.what());
    }
  }
  waitset.attach(requests, kRequestsTag);
  waitset.attach(stop_guard.entity(), kStopTag);
  waitset.attach(loads_guard.entity(), kLoadsTag);
  waitset.attach(snapshot_guard.entity(), kSnapshotTag);
  waitset.attach(writer_wake.entity(), kWritersTag);
  for (const dds::Entity* w : {&update_writer, &compact_update_writer}) {
    dds::notify_matches(*w);
    waitset.attach(*w, kWatchersTag);
  }
  if (!c.journal.dir.empty()) {
    journal = std::make_unique<Journal>(c.journal, handler);  // recovery: replays the log into the handler
    handler.set_on_stored([this](const Reply& reply) { journal->on_stored(reply); });
    journal->set_on_snapshot_written([this] { snapshot_guard.trigger(); });
  }
  handler.set_on_load_done([this] { loads_guard.trigger(); });
}

Service::Impl::~Impl() {
  handler.set_on_load_done({});  // loads finishing later must not touch the deleted guard
  handler.set_on_stored({});
}

const std::string& Service::Impl::subject_of(dds_instance_handle_t sender) {
  static const std::string none;
  if (config.security.empty() || sender == 0) return none;
  auto it = subjects.find(sender);
  if (it == subjects.end()) {
    // Access control let only the user's identity create a writer in "surfeledit.req.<user>"
    // (its permissions), so the partition names the authenticated subject.
    const std::vector<std::string> parts = dds::matched_writer_partitions(request_reader, sender);
    std::string user = parts.size() == 1 ? request_partition_user(parts[0]) : std::string();
    if (subjects.size() >= kMaxSubjects) subjects.clear();  // bounded: re-read on the next request
    it = subjects.emplace(sender, std::move(user)).first;
    if (!it->second.empty()) logger()->info("request writer {:x} is user '{}'", sender, it->second);
  }
  return it->second;
}

void Service::Impl::serve_available() {
  while (!stopping.load()) {
    dds::Loan<surfeledit_proto_Request> loan(request_reader.get(), kTakeBatch);
    if (loan.size() == 0) return;
    // Samples come grouped by instance (client); serve them in the order they were written.
    std::vector<std::size_t> order(loan.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return loan.info(a).source_timestamp < loan.info(b).source_timestamp;
    });
    for (std::size_t i : order) {
      if (!loan.info(i).valid_data) continue;  // instance state change only (e.g. a client left)
      serve(loan.sample(i), loan.info(i).publication_handle);
      flush_journal(false);  // a group whose deadline passed during a long batch
      if (journal) journal->maybe_snapshot();  // between two requests: the state matches the log
      if (stopping.load()) return;
    }
  }
}

void Service::Impl::serve(const surfeledit_proto_Request& request, dds_instance_handle_t sender) {
  std::vector<UpdateEvent> events;
  std::shared_ptr<const Reply> reply;
  try {
    Command command = decode(request);
    command.sender = sender;
    command.subject = subject_of(sender);
    if (journal) {
      journal->serving(&request);
      if (request.op == surfeledit_proto_OP_LOAD_FILE) journal->keep_for_later(request);
    }
    reply = handler.handle(command, events);
    if (journal) journal->serving(nullptr);
    // nullptr: refused without a reply (a spoofed client id), or a file load that replies when it
    // finished (finish_loads); either way nothing to send or publish now.
    if (!reply) return;
  } catch (const std::exception& e) {
    // handle() turns every failure into a reply; this is the last resort (e.g. out of memory there).
    logger()->error("request {}#{} could not be handled: {}", str(request.client_id), request.request_id, e.what());
    auto fallback = std::make_shared<Reply>();
    fallback->client_id = str(request.client_id);
    fallback->request_id = request.request_id;
    fallback->status = Status::Internal;
    fallback->message = std::string("internal error: ") + e.what();
    reply = std::move(fallback);
    events.clear();
    if (journal) journal->serving(nullptr);
  }
  emit(std::move(reply), events);
}

void Service::Impl::emit(std::shared_ptr<const Reply> reply, const std::vector<UpdateEvent>& events) {
  if (!journal || journal->idle()) {
    if (journal && journal->failed()) return;  // the op is not durable: never acknowledged
    if (reply) send(*reply);
    for (const UpdateEvent& event : events) publish(event);
    return;
  }
  // Waiting for the group's fsync: the updates are copied now (the model moves on), written after.
  auto prepared = std::make_shared<std::vector<PreparedUpdate>>();
  for (const UpdateEvent& event : events) {
    try {
      const bool has_surfels = event.all_rows || !event.rows.empty();
      prepared->push_back(prepare_update(event, has_surfels ? handler.model_of(event.session) : nullptr));
    } catch (const std::exception& e) {
      logger()->warn("update of session '{}' v{} ({}) not published: {}", event.session, event.version, event.cause,
                     e.what());
    }
  }
  journal->after_durable([this, reply, prepared] {
    if (reply) send(*reply);
    for (PreparedUpdate& update : *prepared) {
      try {
        if (!publisher) {
          write_update(update);
        } else if (!publisher->push(update)) {
          publisher->push_anyway(std::move(update));  // bounded by the group's few milliseconds of ops
        }
      } catch (const std::exception& e) {
        logger()->warn("update of session '{}' v{} not published: {}", update.session, update.version, e.what());
      }
    }
  });
}

void Service::Impl::flush_journal(bool force) {
  if (!journal) return;
  journal->flush(force);
  if (journal->failed()) throw JournalError(journal->failure());
}

void Service::Impl::send(const Reply& reply) {
  try {
    const dds::Entity& writer = reply.client_id.empty() ? reply_writer : client_replies.for_client(reply.client_id);
    if (!reply.wire.empty()) {  // restored from a journal snapshot: the reply as it was first sent
      const journal::ReplySample sample(reply.wire);
      dds::write(writer, &sample.get(), "dds_write(reply)");
      return;
    }
    const ReplyView view(reply);
    dds::write(writer, view.get(), "dds_write(reply)");
  } catch (const std::exception& e) {
    logger()->error("reply to {}#{} not sent: {}", reply.client_id, reply.request_id, e.what());
  }
}

void Service::Impl::finish_loads() {
  loads_guard.clear();  // before taking: a load finishing meanwhile triggers it again
  std::vector<UpdateEvent> events;
  std::vector<std::shared_ptr<const Reply>> replies;
  try {
    replies = handler.finish_loads(events);
  } catch (const std::exception& e) {
    logger()->error("finished file loads could not be committed: {}", e.what());
    return;
  }
  // Replies first, then the updates (as without a journal).
  for (std::size_t i = 0; i + 1 < replies.size(); ++i) emit(replies[i], {});
  emit(replies.empty() ? nullptr : replies.back(), events);
}

void Service::Impl::check_leases() {
  writer_wake.clear();
  for (const dds::WriterEvents::Event& e : writer_events.take()) {
    if (e.alive) {
      handler.writer_alive(e.writer);
    } else {
      subjects.erase(e.writer);
      handler.writer_lost(e.writer);
    }
  }
  std::vector<UpdateEvent> events;
  std::vector<Expiry> expiries;
  const std::vector<std::string> expired = handler.expire_leases(events, journal ? &expiries : nullptr);
  for (const Expiry& e : expiries) journal->on_expired(e);
  emit(nullptr, events);
  // Returns at once: the writer is deleted on ReplyWriters' deleter thread (a dead client's writer
  // lingers in dds_delete for Cyclone's WriterLingerDuration, 1 s by default).
  for (const std::string& client : expired) client_replies.drop(client);
}

dds_duration_t Service::Impl::next_wake() const {
  dds_duration_t sleep = DDS_INFINITY;
  if (const auto next = handler.next_lease_check()) sleep = DDS_MSECS(next->count() + 1);
  if (journal && journal->deadline()) {
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(*journal->deadline() - Journal::Clock::now());
    sleep = std::min<dds_duration_t>(sleep, DDS_USECS(std::max<std::int64_t>(left.count(), 0) + 1));
  }
  return sleep;
}

void Service::Impl::check_domain() {
  if (!domain_guard) return;
  const std::optional<ServerMarker> other = domain_guard->earlier_server();
  domain_guard.reset();
  if (!other) return;
  throw DomainTakenError("DDS domain " + std::to_string(config.domain) + " already has a surfeledit server (pid " +
                         std::to_string(other->pid) + " on host '" + other->host +
                         "'): stop it or choose another --domain");
}

Service::Service(ServiceConfig config) : impl_(std::make_unique<Impl>(config)) { impl_->check_domain(); }

Service::~Service() = default;

void Service::run() {
  Impl& s = *impl_;
  logger()->debug("serving requests on domain {}", s.config.domain);
  s.check_leases();  // leases of clients recovered from the journal run already
  s.flush_journal(true);
  while (!s.stopping.load()) {
    s.waitset.wait(s.next_wake());
    if (s.stopping.load()) break;
    s.flush_journal(false);
    s.greet_watchers();
    s.finish_loads();
    s.serve_available();
    s.check_leases();
    if (s.journal) {
      s.snapshot_guard.clear();     // before looking: a snapshot finishing meanwhile triggers it again
      s.journal->maybe_snapshot();  // a written snapshot's record; expiries count as records too
    }
    // The request reader is empty (serve_available took until nothing was left): the open group is
    // committed now rather than at its deadline, so a lone client does not wait for group_ms; requests
    // that arrive during this fsync form the next group (PROTOCOL.md "Journal").
    s.flush_journal(true);
  }
  if (s.journal) s.journal->finish_snapshot();  // a snapshot in flight gets its record
  s.flush_journal(true);  // the last group's replies go out before stopping
  s.stop_publisher();
  logger()->info("stopped");
}

void Service::stop() {
  impl_->stopping.store(true);
  impl_->stop_guard.trigger();
}

}  // namespace surfeledit::service
