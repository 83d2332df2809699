// One server per DDS domain (domain_guard.hpp).
#include "domain_guard.hpp"

#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <sstream>
#include <tuple>
#include <vector>

namespace surfeledit::service {

namespace {

constexpr const char* kMarkerTag = "surfeledit-server";

// The user data of a writer's QoS as text ("" when it has none).
std::string user_data_of(const dds_qos_t* qos) {
  void* value = nullptr;
  std::size_t size = 0;
  if (!qos || !dds_qget_userdata(qos, &value, &size) || !value) return {};
  std::string text(static_cast<const char*>(value), size);
  dds_free(value);
  return text;
}

// Parses all of `text` as a decimal integer (optional sign, at least one digit, in range).
bool whole_number(const char* text, std::int64_t& value) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text, &end, 10);
  if (end == text || *end != '\0' || errno == ERANGE) return false;
  value = static_cast<std::int64_t>(v);
  return true;
}

}  // namespace

ServerMarker ServerMarker::of_this_process() {
  ServerMarker m;
  m.start_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                   std::chrono::system_clock::now().time_since_epoch())
                   .count();
  m.pid = static_cast<std::int64_t>(::getpid());
  std::array<char, 256> name{};
  if (::gethostname(name.data(), name.size() - 1) == 0) m.host = name.data();
  return m;
}

std::string ServerMarker::text() const {
  std::ostringstream out;
  out << kMarkerTag << " start=" << start_ns << " pid=" << pid << " host=" << host;
  return out.str();
}

std::optional<ServerMarker> ServerMarker::parse(const std::string& text) {
  std::istringstream in(text);
  std::string tag, start, pid, host;
  if (!(in >> tag >> start >> pid) || tag != kMarkerTag) return std::nullopt;
  std::getline(in >> std::ws, host);
  if (start.rfind("start=", 0) != 0 || pid.rfind("pid=", 0) != 0 || host.rfind("host=", 0) != 0) return std::nullopt;
  ServerMarker m;
  if (!whole_number(start.c_str() + 6, m.start_ns) || !whole_number(pid.c_str() + 4, m.pid)) return std::nullopt;
  m.host = host.substr(5);
  return m;
}

bool ServerMarker::precedes(const ServerMarker& other) const {
  return std::tie(start_ns, pid, host) < std::tie(other.start_ns, other.pid, other.host);
}

DomainGuard::DomainGuard(const dds::Entity& participant, const dds::Entity& reply_topic, ServerMarker self,
                         dds_duration_t window_ns)
    : self_(std::move(self)), deadline_ns_(dds_time() + window_ns) {
  dds::Qos qos = dds::protocol_qos();
  qos.ignore_local_participant();
  probe_ = dds::make_reader(participant, reply_topic, qos);
  dds::check(dds_set_status_mask(probe_.get(), DDS_SUBSCRIPTION_MATCHED_STATUS), "dds_set_status_mask");
  waitset_ = dds::Entity(dds_create_waitset(participant.get()), "dds_create_waitset");
  dds::check(dds_waitset_attach(waitset_.get(), probe_.get(), 0), "dds_waitset_attach");
}

std::optional<ServerMarker> DomainGuard::scan() const {
  std::optional<ServerMarker> earliest;
  const dds_return_t n = dds::check(dds_get_matched_publications(probe_.get(), nullptr, 0), "dds_get_matched_publications");
  std::vector<dds_instance_handle_t> writers(static_cast<std::size_t>(n));
  const dds_return_t got = n == 0 ? 0
                                  : dds::check(dds_get_matched_publications(probe_.get(), writers.data(), writers.size()),
                                               "dds_get_matched_publications");
  for (dds_return_t i = 0; i < got && i < n; ++i) {
    dds_builtintopic_endpoint_t* data = dds_get_matched_publication_data(probe_.get(), writers[i]);
    if (!data) continue;  // unmatched meanwhile
    const std::optional<ServerMarker> other = ServerMarker::parse(user_data_of(data->qos));
    dds_builtintopic_free_endpoint(data);
    if (other && other->precedes(self_) && (!earliest || other->precedes(*earliest))) earliest = other;
  }
  return earliest;
}

std::optional<ServerMarker> DomainGuard::earlier_server() {
  std::optional<ServerMarker> found = scan();
  while (!found && !expired(dds_time())) {
    std::array<dds_attach_t, 1> triggered{};
    dds::check(dds_waitset_wait_until(waitset_.get(), triggered.data(), triggered.size(), deadline_ns_),
               "dds_waitset_wait_until");
    dds_subscription_matched_status_t status{};  // reading it resets the trigger
    dds::check(dds_get_subscription_matched_status(probe_.get(), &status), "dds_get_subscription_matched_status");
    found = scan();
  }
  waitset_.reset();
  probe_.reset();
  return found;
}

}  // namespace surfeledit::service
