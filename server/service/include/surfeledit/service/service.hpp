// The surfeledit DDS service: serves Request samples from clients with one Reply each and
// publishes Update samples after every change (topics and semantics: proto/PROTOCOL.md).
// Requests are served on the thread that calls run(); Update samples are written, in order, from
// copies the request thread makes after the reply is sent, by a publisher thread of the service or
// by the request thread (ServiceConfig::update_thread).
//
// DDS stays behind the pimpl; this header needs nothing but the standard library.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "surfeledit/service/access.hpp"
#include "surfeledit/service/journal.hpp"

namespace surfeledit::service {

// Who writes the Update samples: a publisher thread (the request loop only copies the changed
// surfels) or the request thread itself. Auto: the thread when there is a core to spare beyond the
// per-session worker threads (on 2 cores with 2 OpenMP workers, a publisher thread made the step
// several times slower: bench/RESULTS.md §3).
enum class UpdateThread { Auto, On, Off };

struct ServiceConfig {
  int domain = 0;                                // DDS domain id of all three topics
  std::uint64_t max_chunk_surfels = 65536;       // surfels per LoadChunk, StatePage and Update sample
  std::uint64_t max_model_surfels = 20'000'000;  // surfels per model (LOAD_BEGIN total, loaded files)
  int threads = 0;                               // worker threads per session for batch work; 0 = all cores
  // Bound of the Update samples waiting for the publisher thread (payload bytes). Beyond it, the
  // queued updates of a session are coalesced into one (PROTOCOL.md, "Updates").
  std::uint64_t max_update_queue_bytes = std::uint64_t(256) << 20;
  UpdateThread update_thread = UpdateThread::Auto;
  std::string data_root;                                  // OP_LOAD_FILE reads only below it; empty: off
  std::uint64_t max_file_bytes = std::uint64_t(1) << 30;  // largest file OP_LOAD_FILE reads (1 GiB)
  // Identity, leases and memory bounds (PROTOCOL.md, "Identity and access", "Leases").
  std::uint64_t client_lease_ms = 2000;  // detach a client whose request writer is gone (not alive / unmatched) this long
  // Keep a session whose last client was detached by its lease (and a detached client's memberships)
  // this long, so that a restarted client with the same id finds them; then drop them.
  std::uint64_t session_grace_ms = 30000;
  std::uint64_t max_client_upload_bytes = std::uint64_t(1200) << 20;  // one client's unfinished uploads
  std::uint64_t max_upload_bytes = std::uint64_t(4096) << 20;         // all unfinished uploads
  std::uint64_t max_reply_cache_bytes = std::uint64_t(64) << 20;      // replies kept for repeated requests
  // DDS Security configuration file (surfeledit/service/security.hpp; PROTOCOL.md, "Security");
  // empty: security off (any participant on the domain may match).
  std::string security;
  // Roles granted to authenticated users (--grant USER=ROLE[:SESSION]; access.hpp); needs `security`.
  std::vector<Grant> grants;
  JournalConfig journal;  // --journal DIR and its durability policy (PROTOCOL.md, "Journal"); dir empty: off
  // How long a starting server looks for another server on its domain before it serves, ms (PROTOCOL.md,
  // "One server per domain"); 0: it does not look.
  std::uint64_t domain_probe_ms = 300;
};

// Another surfeledit server, started earlier, serves the domain: this one does not start.
class DomainTakenError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// The server's exit code on DomainTakenError.
constexpr int kDomainTakenExitCode = 4;

class Service {
 public:
  // Creates the participant, topics, reader and writers, and recovers the journal's sessions when
  // config.journal.dir is set; throws std::runtime_error on DDS failures, std::invalid_argument on
  // a bad config, JournalError when the journal cannot be used and DomainTakenError when an earlier server
  // serves the domain (it waits up to config.domain_probe_ms for discovery to find one).
  explicit Service(ServiceConfig config);
  ~Service();
  Service(const Service&) = delete;
  Service& operator=(const Service&) = delete;

  // Serves requests until stop() is called (blocks on a waitset; never polls). Throws JournalError
  // when a journal append or fsync fails (the replies of the ops it could not record are not sent).
  void run();
  // Makes run() return after the request in progress (run() then writes the updates still queued,
  // for at most 2 s, and stops the publisher thread); callable from any thread, also before run().
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace surfeledit::service
