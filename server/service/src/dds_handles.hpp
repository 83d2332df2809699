// RAII wrappers over the Cyclone DDS C API. Every call's return code is checked; a failure
// throws std::runtime_error("<what>: <dds_strretcode>"). Private to the service library.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "surfeledit/service/security.hpp"

namespace surfeledit::service::dds {

// Returns `rc` when it is not an error, throws std::runtime_error naming `what` otherwise.
dds_return_t check(dds_return_t rc, const char* what);

// Owns one DDS entity handle (participant, topic, reader, writer, waitset, condition) and
// deletes it on destruction. Move-only.
class Entity {
 public:
  Entity() = default;
  Entity(dds_entity_t handle, const char* what) : handle_(check(handle, what)) {}
  ~Entity() { reset(); }
  Entity(Entity&& other) noexcept : handle_(std::exchange(other.handle_, 0)) {}
  Entity& operator=(Entity&& other) noexcept {
    if (this != &other) {
      reset();
      handle_ = std::exchange(other.handle_, 0);
    }
    return *this;
  }
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;

  dds_entity_t get() const { return handle_; }
  // Deletes the entity now (and its children); errors are ignored (e.g. already deleted with its parent).
  void reset();

 private:
  dds_entity_t handle_ = 0;
};

// Owns a QoS object.
class Qos {
 public:
  Qos();
  ~Qos();
  Qos(Qos&& other) noexcept : qos_(std::exchange(other.qos_, nullptr)) {}
  Qos(const Qos&) = delete;
  Qos& operator=(const Qos&) = delete;
  Qos& operator=(Qos&&) = delete;
  const dds_qos_t* get() const { return qos_; }

  Qos& reliable(dds_duration_t max_blocking);
  Qos& keep_all();
  Qos& volatile_durability();
  // Automatic liveliness: Cyclone asserts it for the writer every lease (PROTOCOL.md, "Leases").
  Qos& automatic_liveliness(dds_duration_t lease);
  // Keep the last `depth` samples for readers that match later (durability transient-local).
  Qos& transient_local(int32_t depth);
  // The one partition of a publisher or subscriber.
  Qos& partition(const std::string& name);
  // Several partitions of a subscriber (names or wildcard patterns).
  Qos& partitions(const std::vector<std::string>& names);
  // One participant property (e.g. a "dds.sec.*" DDS Security setting).
  Qos& property(const std::string& name, const std::string& value);
  // User data that remote participants see in this writer's discovery data (domain_guard.hpp).
  Qos& user_data(const std::string& text);
  // A reader that does not match writers of its own participant.
  Qos& ignore_local_participant();

 private:
  dds_qos_t* qos_;
};

// The QoS of all three surfeledit topics (PROTOCOL.md): reliable (max blocking 10 s),
// history keep-all, volatile.
Qos protocol_qos();

// The DDS domain `domain` with the server's transport defaults under the configuration CYCLONEDDS_URI names
// (its settings win): DDSI fragments of 65000 bytes in messages of up to 65500 (Cyclone's defaults: 1344 and
// 14720), so that a large update (a 1M-surfel step: ~18 MB) goes out in ~280 datagrams instead of ~13,500
// fragments; a watcher then has it in about half the time (RESULTS §68). An empty entity when this process
// already has the domain (its participants then use that one's configuration) or for the default domain.
Entity make_domain(dds_domainid_t domain);
// A participant on `domain`; with `properties` (surfeledit/service/security.hpp), a secured one
// (DDS Security plugins loaded, identity authenticated, permissions checked).
Entity make_participant(dds_domainid_t domain, const std::vector<SecurityProperty>& properties = {});
Entity make_topic(const Entity& participant, const dds_topic_descriptor_t* type, const std::string& name,
                  const Qos& qos);
Entity make_reader(const Entity& participant, const Entity& topic, const Qos& qos);
// A reader with a listener (nullptr: none); the listener is copied by Cyclone.
Entity make_reader(const Entity& participant, const Entity& topic, const Qos& qos, const dds_listener_t* listener);
// `parent`: the participant or a publisher.
Entity make_writer(const Entity& parent, const Entity& topic, const Qos& qos);
// A publisher whose QoS names its partition.
Entity make_publisher(const Entity& participant, const Qos& qos);
// A subscriber whose QoS names its partitions.
Entity make_subscriber(const Entity& participant, const Qos& qos);
// The partitions of the remote writer `publication` matched with `reader` (from Cyclone's discovery
// data; under DDS Security that is the partition access control let the writer's identity use);
// empty when the writer is not matched (any more) or uses the default partition.
std::vector<std::string> matched_writer_partitions(const Entity& reader, dds_instance_handle_t publication);
// The number of readers the writer is matched with now.
std::uint32_t matched_readers(const Entity& writer);
// Makes the writer's status condition (an entity attached to a waitset) trigger on new matches.
void notify_matches(const Entity& writer);
// The readers the writer matched since the last call (resets the status and its trigger).
std::uint32_t new_matches(const Entity& writer);
// A read condition on every sample of the reader (any sample, view and instance state).
Entity make_read_condition(const Entity& reader);

// Liveliness and match changes of the remote writers of one reader, as reported by Cyclone's
// listener thread, queued for the thread that serves requests (which a guard condition wakes).
class WriterEvents {
 public:
  struct Event {
    dds_instance_handle_t writer;  // publication handle
    bool alive;                    // false: lost its liveliness or unmatched
  };
  WriterEvents();
  ~WriterEvents();
  WriterEvents(const WriterEvents&) = delete;
  WriterEvents& operator=(const WriterEvents&) = delete;
  // The listener to give the reader; events are pushed to this object and `wake` is triggered.
  const dds_listener_t* listener() const { return listener_; }
  // Sets the guard condition triggered on every event (before the reader is created).
  void wake_with(dds_entity_t guard) { wake_ = guard; }
  // Takes the events queued so far, oldest first.
  std::vector<Event> take();

 private:
  static void on_liveliness(dds_entity_t reader, const dds_liveliness_changed_status_t status, void* arg);
  static void on_matched(dds_entity_t reader, const dds_subscription_matched_status_t status, void* arg);
  void push(dds_instance_handle_t writer, bool alive);

  dds_listener_t* listener_;
  dds_entity_t wake_ = 0;
  std::mutex mutex_;
  std::vector<Event> events_;
};

// A guard condition another thread can trigger to wake a waitset.
class GuardCondition {
 public:
  explicit GuardCondition(const Entity& participant);
  void trigger();
  void clear();
  const Entity& entity() const { return entity_; }

 private:
  Entity entity_;
};

class WaitSet {
 public:
  explicit WaitSet(const Entity& participant);
  // Attaches a condition (or entity); `tag` is returned by wait() when it triggers.
  void attach(const Entity& condition, dds_attach_t tag);
  // Blocks until a condition triggers (or the timeout elapses); returns the triggered tags.
  std::vector<dds_attach_t> wait(dds_duration_t timeout = DDS_INFINITY);

 private:
  Entity entity_;
};

// Samples taken on loan from a reader (dds_take without buffers); the loan is returned on destruction.
template <typename T>
class Loan {
 public:
  // Takes up to `max` samples (fewer when fewer are available; possibly none).
  Loan(dds_entity_t reader_or_condition, std::size_t max)
      : reader_(reader_or_condition), samples_(max, nullptr), infos_(max) {
    const dds_return_t n = check(dds_take(reader_, samples_.data(), infos_.data(), max, static_cast<uint32_t>(max)),
                                 "dds_take");
    count_ = static_cast<std::size_t>(n);
  }
  ~Loan() {
    if (count_ > 0) (void)dds_return_loan(reader_, samples_.data(), static_cast<int32_t>(count_));
  }
  Loan(const Loan&) = delete;
  Loan& operator=(const Loan&) = delete;

  std::size_t size() const { return count_; }
  const T& sample(std::size_t i) const { return *static_cast<const T*>(samples_[i]); }
  const dds_sample_info_t& info(std::size_t i) const { return infos_[i]; }

 private:
  dds_entity_t reader_;
  std::vector<void*> samples_;
  std::vector<dds_sample_info_t> infos_;
  std::size_t count_ = 0;
};

// Writes one sample; throws on failure (e.g. a timeout after the reliable max blocking time).
void write(const Entity& writer, const void* sample, const char* what);

}  // namespace surfeledit::service::dds
