#include "dds_handles.hpp"

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace surfeledit::service::dds {

dds_return_t check(dds_return_t rc, const char* what) {
  if (rc < 0) throw std::runtime_error(std::string(what) + ": " + dds_strretcode(rc));
  return rc;
}

void Entity::reset() {
  if (handle_ > 0) (void)dds_delete(handle_);
  handle_ = 0;
}

Qos::Qos() : qos_(dds_create_qos()) {
  if (!qos_) throw std::runtime_error("dds_create_qos: out of memory");
}

Qos::~Qos() {
  if (qos_) dds_delete_qos(qos_);
}

Qos& Qos::reliable(dds_duration_t max_blocking) {
  dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, max_blocking);
  return *this;
}

Qos& Qos::keep_all() {
  dds_qset_history(qos_, DDS_HISTORY_KEEP_ALL, 0);
  return *this;
}

Qos& Qos::volatile_durability() {
  dds_qset_durability(qos_, DDS_DURABILITY_VOLATILE);
  return *this;
}

Qos& Qos::automatic_liveliness(dds_duration_t lease) {
  dds_qset_liveliness(qos_, DDS_LIVELINESS_AUTOMATIC, lease);
  return *this;
}

Qos& Qos::transient_local(int32_t depth) {
  dds_qset_durability(qos_, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, depth);
  return *this;
}

Qos& Qos::partition(const std::string& name) {
  dds_qset_partition1(qos_, name.c_str());
  return *this;
}

Qos& Qos::partitions(const std::vector<std::string>& names) {
  std::vector<const char*> ps;
  for (const std::string& n : names) ps.push_back(n.c_str());
  dds_qset_partition(qos_, static_cast<std::uint32_t>(ps.size()), ps.data());
  return *this;
}

Qos& Qos::property(const std::string& name, const std::string& value) {
  dds_qset_prop(qos_, name.c_str(), value.c_str());
  return *this;
}

Qos& Qos::user_data(const std::string& text) {
  dds_qset_userdata(qos_, text.data(), text.size());
  return *this;
}

Qos& Qos::ignore_local_participant() {
  dds_qset_ignorelocal(qos_, DDS_IGNORELOCAL_PARTICIPANT);
  return *this;
}

Qos protocol_qos() {
  Qos qos;
  qos.reliable(DDS_SECS(10)).keep_all().volatile_durability();
  return qos;
}

Entity make_domain(dds_domainid_t domain) {
  if (domain == DDS_DOMAIN_DEFAULT) return Entity();
  std::string config =
      "<CycloneDDS><Domain id=\"any\"><General><MaxMessageSize>65500B</MaxMessageSize>"
      "<FragmentSize>65000B</FragmentSize></General></Domain></CycloneDDS>";
  // A list of sources, later ones overriding earlier ones: the user's configuration after the defaults.
  if (const char* uri = std::getenv("CYCLONEDDS_URI"); uri != nullptr && *uri != '\0') config += std::string(",") + uri;
  const dds_entity_t handle = dds_create_domain(domain, config.c_str());
  if (handle == DDS_RETCODE_PRECONDITION_NOT_MET) return Entity();
  return Entity(handle, "dds_create_domain");
}

Entity make_participant(dds_domainid_t domain, const std::vector<SecurityProperty>& properties) {
  if (properties.empty()) return Entity(dds_create_participant(domain, nullptr, nullptr), "dds_create_participant");
  Qos qos;
  for (const auto& p : properties) qos.property(p.name, p.value);
  return Entity(dds_create_participant(domain, qos.get(), nullptr),
                "dds_create_participant with DDS Security (is the identity valid, signed by identity_ca, its "
                "permissions signed by permissions_ca and granting this domain?)");
}

Entity make_topic(const Entity& participant, const dds_topic_descriptor_t* type, const std::string& name,
                  const Qos& qos) {
  const std::string what = "dds_create_topic(" + name + ")";
  return Entity(dds_create_topic(participant.get(), type, name.c_str(), qos.get(), nullptr), what.c_str());
}

Entity make_reader(const Entity& participant, const Entity& topic, const Qos& qos) {
  return Entity(dds_create_reader(participant.get(), topic.get(), qos.get(), nullptr), "dds_create_reader");
}

Entity make_reader(const Entity& participant, const Entity& topic, const Qos& qos, const dds_listener_t* listener) {
  return Entity(dds_create_reader(participant.get(), topic.get(), qos.get(), listener), "dds_create_reader");
}

WriterEvents::WriterEvents() : listener_(dds_create_listener(this)) {
  if (!listener_) throw std::runtime_error("dds_create_listener: out of memory");
  dds_lset_liveliness_changed(listener_, &WriterEvents::on_liveliness);
  dds_lset_subscription_matched(listener_, &WriterEvents::on_matched);
}

WriterEvents::~WriterEvents() { dds_delete_listener(listener_); }

void WriterEvents::on_liveliness(dds_entity_t, const dds_liveliness_changed_status_t status, void* arg) {
  auto* self = static_cast<WriterEvents*>(arg);
  if (status.alive_count_change > 0) {
    self->push(status.last_publication_handle, true);
  } else if (status.alive_count_change < 0 || status.not_alive_count_change > 0) {
    self->push(status.last_publication_handle, false);
  }
}

void WriterEvents::on_matched(dds_entity_t, const dds_subscription_matched_status_t status, void* arg) {
  if (status.current_count_change < 0) static_cast<WriterEvents*>(arg)->push(status.last_publication_handle, false);
}

void WriterEvents::push(dds_instance_handle_t writer, bool alive) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    events_.push_back(Event{writer, alive});
  }
  if (wake_ > 0) (void)dds_set_guardcondition(wake_, true);
}

std::vector<WriterEvents::Event> WriterEvents::take() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(events_, {});
}

Entity make_writer(const Entity& parent, const Entity& topic, const Qos& qos) {
  return Entity(dds_create_writer(parent.get(), topic.get(), qos.get(), nullptr), "dds_create_writer");
}

Entity make_publisher(const Entity& participant, const Qos& qos) {
  return Entity(dds_create_publisher(participant.get(), qos.get(), nullptr), "dds_create_publisher");
}

Entity make_subscriber(const Entity& participant, const Qos& qos) {
  return Entity(dds_create_subscriber(participant.get(), qos.get(), nullptr), "dds_create_subscriber");
}

std::vector<std::string> matched_writer_partitions(const Entity& reader, dds_instance_handle_t publication) {
  std::vector<std::string> out;
  dds_builtintopic_endpoint_t* data = dds_get_matched_publication_data(reader.get(), publication);
  if (!data) return out;
  std::uint32_t n = 0;
  char** ps = nullptr;
  if (data->qos && dds_qget_partition(data->qos, &n, &ps)) {
    for (std::uint32_t i = 0; i < n; ++i) {
      out.emplace_back(ps[i]);
      dds_free(ps[i]);
    }
    dds_free(ps);
  }
  dds_builtintopic_free_endpoint(data);
  return out;
}

std::uint32_t matched_readers(const Entity& writer) {
  // Not dds_get_publication_matched_status: reading that status resets its change counts, and
  // new_matches() needs them to greet each new watcher (a publish between a match and the greeting
  // would otherwise swallow the greeting).
  const dds_return_t n = dds_get_matched_subscriptions(writer.get(), nullptr, 0);
  check(n, "dds_get_matched_subscriptions");
  return static_cast<std::uint32_t>(n);
}

void notify_matches(const Entity& writer) {
  check(dds_set_status_mask(writer.get(), DDS_PUBLICATION_MATCHED_STATUS), "dds_set_status_mask");
}

std::uint32_t new_matches(const Entity& writer) {
  dds_publication_matched_status_t status{};
  check(dds_get_publication_matched_status(writer.get(), &status), "dds_get_publication_matched_status");
  return status.total_count_change;
}

Entity make_read_condition(const Entity& reader) {
  return Entity(dds_create_readcondition(reader.get(), DDS_ANY_STATE), "dds_create_readcondition");
}

GuardCondition::GuardCondition(const Entity& participant)
    : entity_(dds_create_guardcondition(participant.get()), "dds_create_guardcondition") {}

void GuardCondition::trigger() { check(dds_set_guardcondition(entity_.get(), true), "dds_set_guardcondition"); }

void GuardCondition::clear() { check(dds_set_guardcondition(entity_.get(), false), "dds_set_guardcondition"); }

WaitSet::WaitSet(const Entity& participant) : entity_(dds_create_waitset(participant.get()), "dds_create_waitset") {}

void WaitSet::attach(const Entity& condition, dds_attach_t tag) {
  check(dds_waitset_attach(entity_.get(), condition.get(), tag), "dds_waitset_attach");
}

std::vector<dds_attach_t> WaitSet::wait(dds_duration_t timeout) {
  std::vector<dds_attach_t> triggered(8);
  const dds_return_t n = check(dds_waitset_wait(entity_.get(), triggered.data(), triggered.size(), timeout),
                               "dds_waitset_wait");
  triggered.resize(std::min<std::size_t>(static_cast<std::size_t>(n), triggered.size()));
  return triggered;
}

void write(const Entity& writer, const void* sample, const char* what) { check(dds_write(writer.get(), sample), what); }

}  // namespace surfeledit::service::dds
