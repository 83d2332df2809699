// surfeledit-secure-probe: the permitted client (`client`) and the paired bench (`bench`).
#include <cmath>
#include <cstdio>
#include <thread>

#include "secure_probe.hpp"

namespace surfeledit::probe {

namespace {

// The permitted client: request writer, reply reader in its own partition, update reader.
class Client {
 public:
  Client(int domain, const std::string& security, const std::string& client_id, double timeout_s)
      : client_id_(client_id), timeout_s_(timeout_s) {
    pp_ = check(make_participant(domain, security), "dds_create_participant");
    const auto topic = [&](const dds_topic_descriptor_t& type, const char* name) {
      return check(dds_create_topic(pp_, &type, name, nullptr, nullptr), std::string("topic ") + name);
    };
    const dds_entity_t req_t = topic(kRequestDesc, "surfeledit_request");
    const dds_entity_t rep_t = topic(kReplyDesc, "surfeledit_reply");
    const dds_entity_t upd_t = topic(kUpdateDesc, "surfeledit_update");
    dds_qos_t* wq = protocol_qos(false, true);
    writer_ = check(dds_create_writer(pp_, req_t, wq, nullptr), "request writer");
    dds_delete_qos(wq);
    replies_ = check(make_reader(pp_, rep_t, reply_partition(client_id), true), "reply reader");
    updates_ = check(make_reader(pp_, upd_t, "", false), "update reader");
    ws_ = check(dds_create_waitset(pp_), "waitset");
    cond_ = check(dds_create_readcondition(replies_, DDS_ANY_STATE), "readcondition");
    check(dds_waitset_attach(ws_, cond_, 0), "attach");
  }
  ~Client() { dds_delete(pp_); }

  // Waits until the server's request reader and update writer are matched.
  bool wait_matched() {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s_);
    while (Clock::now() < deadline) {
      dds_publication_matched_status_t pm;
      dds_subscription_matched_status_t sm;
      check(dds_get_publication_matched_status(writer_, &pm), "matched");
      check(dds_get_subscription_matched_status(updates_, &sm), "matched");
      if (pm.current_count > 0 && sm.current_count > 0) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }

  // Writes `r` and waits for its reply; returns the status (-1: no reply in time) and the round trip.
  int call(surfeledit_proto_Request& r, double* ms = nullptr, std::string* message = nullptr) {
    const auto t0 = Clock::now();
    check(dds_write(writer_, &r), "dds_write");
    const auto deadline = t0 + std::chrono::duration<double>(timeout_s_);
    while (Clock::now() < deadline) {
      void* samples[8] = {nullptr};
      dds_sample_info_t infos[8];
      const dds_return_t n = check(dds_take(replies_, samples, infos, 8, 8), "take");
      int status = -2;
      for (dds_return_t i = 0; i < n; ++i) {
        if (!infos[i].valid_data) continue;
        const auto* rep = static_cast<const surfeledit_proto_Reply*>(samples[i]);
        if (rep->request_id == r.request_id && std::strcmp(rep->client_id, r.client_id) == 0) {
          status = static_cast<int>(rep->status);
          if (message) *message = std::string(rep->field) + ": " + rep->message;
        }
      }
      if (n > 0) dds_return_loan(replies_, samples, n);
      if (status != -2) {
        if (ms) *ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        return status;
      }
      const dds_duration_t left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - Clock::now()).count();
      if (left > 0) dds_waitset_wait(ws_, nullptr, 0, left);
    }
    return -1;
  }

  int updates() { return updates_seen_ += drain<surfeledit_proto_Update>(updates_); }

  std::uint64_t next_id() { return next_id_++; }
  const std::string& id() const { return client_id_; }

 private:
  std::string client_id_;
  double timeout_s_;
  dds_entity_t pp_ = 0, writer_ = 0, replies_ = 0, updates_ = 0, ws_ = 0, cond_ = 0;
  std::uint64_t next_id_ = 1;
  int updates_seen_ = 0;
};

// Slab (zero region) and a sphere above it (one region): positions, normals, radii.
struct Scene {
  std::vector<double> positions, normals, radii;
  std::vector<uint64_t> zero, one;
};

Scene make_scene(std::size_t total) {
  Scene s;
  const std::size_t n_sphere = total / 2, side = static_cast<std::size_t>(std::sqrt(double(total - n_sphere)));
  const double spacing = 3.0 / double(side);
  for (std::size_t i = 0; i < side; ++i) {
    for (std::size_t j = 0; j < side; ++j) {
      s.positions.insert(s.positions.end(), {-1.5 + spacing * (i + 0.5), -1.5 + spacing * (j + 0.5), 0.0});
      s.normals.insert(s.normals.end(), {0.0, 0.0, 1.0});
      s.radii.push_back(spacing * 0.75);
      s.zero.push_back(s.zero.size());
    }
  }
  const double golden = M_PI * (3.0 - std::sqrt(5.0)), r = 0.5;
  const double sphere_radius = r * std::sqrt(4.0 / double(n_sphere)) * 0.75;
  for (std::size_t k = 0; k < n_sphere; ++k) {  // Fibonacci sphere, centre (0, 0, 1)
    const double z = 1.0 - 2.0 * (double(k) + 0.5) / double(n_sphere), rho = std::sqrt(1.0 - z * z);
    const double phi = golden * double(k);
    const double nx = rho * std::cos(phi), ny = rho * std::sin(phi);
    s.one.push_back(s.radii.size());
    s.positions.insert(s.positions.end(), {r * nx, r * ny, 1.0 + r * z});
    s.normals.insert(s.normals.end(), {nx, ny, z});
    s.radii.push_back(sphere_radius);
  }
  return s;
}

// Prints `what=<status>` (and `what_error=` unless OK); returns the exit code it implies.
int report(const char* what, int status, const std::string& msg) {
  std::printf("%s=%d\n", what, status);
  if (status != 0) std::printf("%s_error=%s\n", what, msg.c_str());
  std::fflush(stdout);
  return status == 0 ? 0 : status == -1 ? 2 : 3;
}

// Opens the session, uploads the scene, sets the regions, configures algorithm "none"; returns an
// exit code (0: all OK).
int prepare(Client& c, const Args& a) {
  if (!c.wait_matched()) {
    std::printf("matched=0\n");
    return 2;
  }
  std::printf("matched=1\n");
  const std::string& id = c.id();
  std::string msg;
  auto r = blank_request(id, c.next_id(), a.session, surfeledit_proto_OP_OPEN_SESSION);
  if (int e = report("open", c.call(r, nullptr, &msg), msg)) return e;

  Scene s = make_scene(a.surfels);
  std::printf("surfels=%zu\n", s.radii.size());
  surfeledit_proto_LoadBegin begin{s.radii.size(), true};
  r = blank_request(id, c.next_id(), a.session, surfeledit_proto_OP_LOAD_BEGIN);
  one(r.load_begin, begin);
  if (int e = report("load_begin", c.call(r, nullptr, &msg), msg)) return e;
  surfeledit_proto_LoadChunk chunk{};
  chunk.offset = 0;
  many(chunk.positions, s.positions);
  many(chunk.normals, s.normals);
  many(chunk.radii, s.radii);
  r = blank_request(id, c.next_id(), a.session, surfeledit_proto_OP_LOAD_CHUNK);
  one(r.load_chunk, chunk);
  if (int e = report("load_chunk", c.call(r, nullptr, &msg), msg)) return e;
  r = blank_request(id, c.next_id(), a.session, surfeledit_proto_OP_LOAD_COMMIT);
  if (int e = report("load_commit", c.call(r, nullptr, &msg), msg)) return e;

  surfeledit_proto_SetRegions regions{};
  many(regions.zero.ids, s.zero);
  many(regions.one.ids, s.one);
  r = blank_request(id, c.next_id(), a.session, surfeledit_proto_OP_SET_REGIONS);
  one(r.set_regions, regions);
  if (int e = report("set_regions", c.call(r, nullptr, &msg), msg)) return e;

  surfeledit_proto_Setting setting{};
  setting.name = const_cast<char*>("algorithm");
  setting.kind = surfeledit_proto_SETTING_TEXT;
  setting.text = const_cast<char*>("none");
  surfeledit_proto_Configure configure{};
  one(configure.settings, setting);
  r = blank_request(id, c.next_id(), a.session, surfeledit_proto_OP_CONFIGURE);
  one(r.configure, configure);
  return report("configure", c.call(r, nullptr, &msg), msg);
}

// Step `i` (oscillating in place, as bench_step_rtt.py); `ms`: write to reply. Returns an exit code.
int step(Client& c, const Args& a, int i, double* ms) {
  const double sign = i % 2 == 0 ? 1.0 : -1.0;
  surfeledit_proto_Deform d{};
  d.translation = {0.0, 0.01 * sign, 0.005 * sign};
  d.axis = {1.0, 0.0, 0.0};
  d.angle = 0.05 * sign;
  d.blend = const_cast<char*>("smooth");
  auto r = blank_request(c.id(), c.next_id(), a.session, surfeledit_proto_OP_DEFORM);
  one(r.deform, d);
  std::string msg;
  return report("deform", c.call(r, ms, &msg), msg);
}

int close_session(Client& c, const Args& a) {
  auto r = blank_request(c.id(), c.next_id(), a.session, surfeledit_proto_OP_CLOSE_SESSION);
  std::string msg;
  return report("close", c.call(r, nullptr, &msg), msg);
}

}  // namespace

int run_client(const Args& a) {
  Client c(a.domain, a.security, a.client_id, a.timeout_s);
  if (int e = prepare(c, a)) return e;
  for (int i = 0; i < a.steps; ++i) {
    double ms = 0;
    if (int e = step(c, a, i, &ms)) return e;
    std::printf("step_ms=%.4f\n", ms);
  }
  // The step updates follow their replies: wait a little for the last one.
  const auto deadline = Clock::now() + std::chrono::seconds(2);
  int updates = c.updates();
  while (updates < a.steps + 1 && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    updates = c.updates();
  }
  std::printf("updates=%d\n", updates);
  return close_session(c, a);
}

// Two clients in this process, one secured (--domain, --security) and one plain (--plain-domain),
// each with the same session; their steps alternate (on, off, then off, on, ...), so load changes hit
// both arms alike. Prints on_ms= and off_ms= per step.
int run_bench(const Args& a) {
  if (a.security.empty() || a.plain_domain < 0) {
    throw std::invalid_argument("bench needs --security and --plain-domain");
  }
  Client on(a.domain, a.security, a.client_id + "-on", a.timeout_s);
  Client off(a.plain_domain, "", a.client_id + "-off", a.timeout_s);
  if (int e = prepare(on, a)) return e;
  if (int e = prepare(off, a)) return e;
  for (int i = 0; i < a.steps; ++i) {
    double ms_on = 0, ms_off = 0;
    const bool on_first = i % 4 < 2;  // each arm takes each oscillation phase first equally often
    for (int k = 0; k < 2; ++k) {
      const bool secured = (k == 0) == on_first;
      if (int e = step(secured ? on : off, a, i, secured ? &ms_on : &ms_off)) return e;
    }
    std::printf("on_ms=%.4f\noff_ms=%.4f\n", ms_on, ms_off);
  }
  std::fflush(stdout);
  if (int e = close_session(on, a)) return e;
  return close_session(off, a);
}

}  // namespace surfeledit::probe
