// surfeledit-server: serves surfel editing sessions over DDS until SIGINT/SIGTERM.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <pthread.h>
#include <signal.h>

#include <cstdint>
#include <exception>
#include <string>
#include <thread>

#include "surfeledit/core/util.hpp"
#include "surfeledit/service/service.hpp"

namespace {

// Blocks SIGINT and SIGTERM in the calling thread (and every thread started after it), so
// that only the dedicated signal thread receives them through sigwait.
sigset_t block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

}  // namespace

int main(int argc, char** argv) {
  surfeledit::service::ServiceConfig config;
  std::string log_level = "info";

  CLI::App app{"surfeledit-server: interactive editing of point-sampled surfaces over Cyclone DDS"};
  app.set_config("--config", "", "Read options from an INI or TOML file (keys as the long option names)");
  app.add_option("--domain", config.domain, "DDS domain id")->capture_default_str()->check(CLI::Range(0, 232));
  app.add_option("--log-level", log_level, "Log level")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  app.add_option("--max-chunk-surfels", config.max_chunk_surfels,
                 "Surfels per LoadChunk, StatePage and Update sample")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 24));
  app.add_option("--max-model-surfels", config.max_model_surfels, "Surfels per model")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(INT32_MAX)));
  app.add_option("--threads", config.threads,
                 "Worker threads per session for batch work, and every tool's starting threads setting (0: all cores)")
      ->capture_default_str()
      ->check(CLI::Range(0, surfeledit::hardware_threads()));
  app.add_option("--data-root", config.data_root,
                 "Directory below which OP_LOAD_FILE may read model files (symlinks and .. are resolved; "
                 "nothing outside it is read); without it, file loading is off")
      ->check(CLI::ExistingDirectory);
  std::uint64_t max_file_mb = config.max_file_bytes >> 20;
  app.add_option("--max-file-mb", max_file_mb, "Largest model file OP_LOAD_FILE reads, in MiB")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 20));
  std::uint64_t update_queue_mb = config.max_update_queue_bytes >> 20;
  app.add_option("--max-update-queue-mb", update_queue_mb,
                 "Update samples waiting for the publisher thread, in MiB; beyond it a session's queued updates "
                 "are merged into one")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 20));
  std::string update_thread = "auto";
  app.add_option("--update-thread", update_thread,
                 "Write Update samples on a publisher thread (on), on the request thread (off), or on a thread "
                 "when a core is left beyond --threads (auto)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "on", "off"}));
  // Identity, leases and memory bounds (proto/PROTOCOL.md, "Identity and access" and "Leases").
  app.add_option("--client-lease-ms", config.client_lease_ms,
                 "Detach a client whose request writer has not been alive (DDS liveliness) or matched for this long: "
                 "its sessions are closed and its unfinished uploads freed")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(3'600'000)));
  app.add_option("--session-grace-ms", config.session_grace_ms,
                 "Keep a session whose last client was detached by its lease (and that client's memberships) this "
                 "long, so that a restarted client with the same client id finds it; then drop it (0: at once)")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(0), std::uint64_t(86'400'000)));
  std::uint64_t client_upload_mb = config.max_client_upload_bytes >> 20;
  app.add_option("--max-client-upload-mb", client_upload_mb,
                 "Memory of one client's unfinished uploads, MiB (reserved as chunks arrive)")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 30));
  std::uint64_t upload_mb = config.max_upload_bytes >> 20;
  app.add_option("--max-upload-mb", upload_mb, "Memory of all clients' unfinished uploads, MiB")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 30));
  std::uint64_t reply_cache_mb = config.max_reply_cache_bytes >> 20;
  app.add_option("--max-reply-cache-mb", reply_cache_mb, "Replies kept for repeated requests, MiB (estimated)")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 20));
  app.add_option("--security", config.security,
                 "DDS Security configuration file (identity, CAs, signed governance and permissions; "
                 "scripts/make_security.py writes one per user): participants must authenticate and hold "
                 "permissions, discovery and data are encrypted; without it, security is off")
      ->check(CLI::ExistingFile);
  std::vector<std::string> grants;
  app.add_option("--grant", grants,
                 "USER=ROLE[:SESSION] (repeatable; needs --security): the authenticated USER (certificate CN, "
                 "writing requests in partition surfeledit.req.USER) may join SESSION, or every session, as "
                 "ROLE (editor or viewer) without a token")
      ->check([](const std::string& text) {
        try {
          surfeledit::service::parse_grant(text);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      });
  // The journal (proto/PROTOCOL.md, "Journal").
  app.add_option("--journal", config.journal.dir,
                 "Directory of the journal: every accepted op is made durable before its reply is written, and a "
                 "restart with the same directory recovers every session, its history and versions (created if "
                 "missing; one server per directory)");
  std::string journal_sync = "op";
  app.add_option("--journal-sync", journal_sync,
                 "When journal records reach the disk: fsync before every reply (op), or one fsync per group, "
                 "committed when no more requests are ready or after --journal-group-ms, whose replies wait "
                 "for it (group)")
      ->capture_default_str()
      ->check(CLI::IsMember({"op", "group"}));
  app.add_option("--journal-group-ms", config.journal.group_ms,
                 "Group commit: the longest a reply waits for its group's fsync, ms")
      ->capture_default_str()
      ->check(CLI::Range(1, 10'000));
  app.add_option("--journal-rejoin-ms", config.journal.rejoin_ms,
                 "After recovery, how long a recovered client may take to send a request before it is detached")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(3'600'000)));
  app.add_option("--journal-snapshot-records", config.journal.snapshot_records,
                 "Take a snapshot of every session and the service state after this many journal records, start a "
                 "new log segment and delete the segments and snapshots before the previous snapshot, so recovery "
                 "restores the newest snapshot and replays only the records after it (0: never by count). Deferred "
                 "while an upload is unfinished, a file load runs or a session is not snapshottable")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(0), std::uint64_t(1) << 40));
  app.add_option("--journal-snapshot-mb", config.journal.snapshot_mb,
                 "Take a snapshot (as --journal-snapshot-records) once the log since the last one exceeds this many "
                 "MiB (0: never by size)")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(0), std::uint64_t(1) << 20));
  app.add_option("--domain-probe-ms", config.domain_probe_ms,
                 "How long the server looks for another surfeledit server on its domain before serving; it exits "
                 "with code 4 if one started earlier (two servers would both answer every request; 0: no check)")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(0), std::uint64_t(60'000)));
  CLI11_PARSE(app, argc, argv);
  for (const std::string& g : grants) config.grants.push_back(surfeledit::service::parse_grant(g));
  config.journal.sync = journal_sync == "group" ? surfeledit::service::JournalSync::Group
                                                : surfeledit::service::JournalSync::Op;
  config.max_client_upload_bytes = client_upload_mb << 20;
  config.max_upload_bytes = upload_mb << 20;
  config.max_reply_cache_bytes = reply_cache_mb << 20;
  config.update_thread = update_thread == "on"    ? surfeledit::service::UpdateThread::On
                         : update_thread == "off" ? surfeledit::service::UpdateThread::Off
                                                  : surfeledit::service::UpdateThread::Auto;
  config.max_update_queue_bytes = update_queue_mb << 20;
  config.max_file_bytes = max_file_mb << 20;

  auto log = spdlog::stderr_color_mt("surfeledit");
  log->set_level(spdlog::level::from_str(log_level));
  log->flush_on(spdlog::level::info);

  sigset_t stop_signals = block_stop_signals();
  try {
    surfeledit::service::Service service(config);
    // Waits for SIGINT/SIGTERM and stops the service; woken by pthread_kill if run() fails.
    std::thread signal_thread([&] {
      int signal_number = 0;
      if (sigwait(&stop_signals, &signal_number) == 0) {
        log->info("signal {} received, stopping", signal_number);
      }
      service.stop();
    });
    if (config.data_root.empty()) log->info("file loading is off (no --data-root)");
    else log->info("file loading reads below '{}' (files up to {} MiB)", config.data_root, max_file_mb);
    if (config.security.empty()) log->info("DDS Security is off (no --security)");
    else log->info("DDS Security on: '{}'", config.security);
    log->info("surfeledit-server ready on domain {}", config.domain);
    try {
      service.run();
    } catch (...) {
      pthread_kill(signal_thread.native_handle(), SIGTERM);
      signal_thread.join();
      throw;
    }
    signal_thread.join();
  } catch (const surfeledit::service::JournalError& e) {
    log->critical("surfeledit-server failed: journal: {}", e.what());
    return surfeledit::service::kJournalExitCode;
  } catch (const surfeledit::service::DomainTakenError& e) {
    log->critical("surfeledit-server not started: {}", e.what());
    return surfeledit::service::kDomainTakenExitCode;
  } catch (const std::exception& e) {
    log->critical("surfeledit-server failed: {}", e.what());
    return 1;
  }
  log->info("surfeledit-server exited cleanly");
  return 0;
}
