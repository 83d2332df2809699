// Service::Impl's update path: updates prepared on the request thread, merged when the publisher's
// queue is over its bound, and written in the encodings that watchers read (PROTOCOL.md "Updates").
#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "service_impl.hpp"
#include "surfeledit/core/util.hpp"
#include "surfeledit/service/log.hpp"
#include "surfeledit/service/sample_views.hpp"

namespace surfeledit::service {

std::unique_ptr<UpdatePublisher> Service::Impl::make_publisher(const ServiceConfig& c) {
  const unsigned hw = static_cast<unsigned>(hardware_threads());
  const unsigned workers = c.threads == 0 ? hw : static_cast<unsigned>(c.threads);
  const bool on = c.update_thread == UpdateThread::On || (c.update_thread == UpdateThread::Auto && workers < hw);
  logger()->info("updates are written {} ({} core(s), {} worker thread(s) per session)",
                 on ? "by a publisher thread" : "on the request thread", hw, workers);
  if (!on) return nullptr;
  return std::make_unique<UpdatePublisher>([this](const PreparedUpdate& u) { write_update(u); },
                                           static_cast<std::size_t>(c.max_update_queue_bytes));
}

void Service::Impl::publish(const UpdateEvent& event) {
  try {
    const bool has_surfels = event.all_rows || !event.rows.empty();
    const SurfelModel* model = has_surfels ? handler.model_of(event.session) : nullptr;
    PreparedUpdate update = prepare_update(event, model);
    if (!publisher) {
      write_update(update);
    } else if (!publisher->push(update)) {
      coalesce(event, update);
    }
  } catch (const std::exception& e) {
    logger()->warn("update of session '{}' v{} ({}) not published: {}", event.session, event.version, event.cause,
                   e.what());
  }
}

void Service::Impl::coalesce(const UpdateEvent& event, PreparedUpdate& update) {
  // Causes whose updates add up to "what changed since" (a load replaces the model and a close
  // ends the session: those are never merged).
  static const std::vector<std::string> kIncremental = {"deform", "remove", "regions", "release"};
  const std::size_t queued = publisher->queued_bytes();
  std::vector<PreparedUpdate> pending =
      std::find(kIncremental.begin(), kIncremental.end(), event.cause) == kIncremental.end()
          ? std::vector<PreparedUpdate>{}
          : publisher->take_pending(event.session, event.version, kIncremental);
  if (pending.empty()) {
    logger()->warn("update queue over its bound ({:.1f} of {:.1f} MB queued): session '{}' v{} ({}) queued anyway "
                   "(nothing of this session to merge it with)",
                   static_cast<double>(queued) / 1e6, static_cast<double>(publisher->max_queued_bytes()) / 1e6,
                   event.session, event.version, event.cause);
    publisher->push_anyway(std::move(update));
    return;
  }
  // One update with everything that changed since the oldest merged one; the newest one's cause,
  // step and collision state.
  const std::uint64_t since = pending.front().version - 1;
  std::optional<UpdateEvent> merged = handler.changes_event(event.session, since);
  if (!merged) throw std::logic_error("session '" + event.session + "' vanished while its update was merged");
  merged->cause = event.cause;
  merged->author = event.author;  // the newest's (PROTOCOL.md, "Updates")
  merged->step = event.step;
  merged->detected = event.detected;
  merged->colliding = event.colliding;
  merged->removed.insert(merged->removed.end(), event.removed.begin(), event.removed.end());
  std::sort(merged->removed.begin(), merged->removed.end());
  merged->removed.erase(std::unique(merged->removed.begin(), merged->removed.end()), merged->removed.end());
  const SurfelModel* model = handler.model_of(event.session);
  PreparedUpdate combined = prepare_update(*merged, model);
  logger()->warn("update queue over its bound ({:.1f} of {:.1f} MB queued): merged {} queued update(s) of session "
                 "'{}' (v{}..v{}) and v{} into one update v{} ({} surfels)",
                 static_cast<double>(queued) / 1e6, static_cast<double>(publisher->max_queued_bytes()) / 1e6,
                 pending.size(), event.session, pending.front().version, pending.back().version, event.version,
                 combined.version, combined.surfels());
  publisher->push_anyway(std::move(combined));
}

void Service::Impl::write_update(const PreparedUpdate& update) {
  // Each encoding costs its serialisation only while some watcher reads it (updates are volatile: a
  // reader that is not matched yet would not get the sample either).
  const std::uint32_t parts = update_parts(update, config.max_chunk_surfels);
  const bool full = dds::matched_readers(update_writer) > 0;
  const bool compact = dds::matched_readers(compact_update_writer) > 0;
  for (std::uint32_t part = 0; part < parts; ++part) {
    const UpdateChunk chunk = update_chunk(update, part, config.max_chunk_surfels);
    if (full) dds::write(update_writer, UpdateView(chunk).get(), "dds_write(update)");
    if (compact) dds::write(compact_update_writer, UpdateView(chunk, true).get(), "dds_write(compact update)");
  }
  logger()->debug("update '{}' v{} {}: {} part(s){}{}", update.session, update.version, update.cause, parts,
                  full ? ", full" : "", compact ? ", compact" : "");
}

void Service::Impl::greet_watchers() {
  for (const dds::Entity* w : {&update_writer, &compact_update_writer}) {
    if (dds::new_matches(*w) == 0) continue;
    PreparedUpdate hello;
    hello.cause = "watch";
    const UpdateView view(update_chunk(hello, 0, config.max_chunk_surfels), w == &compact_update_writer);
    dds::write(*w, view.get(), "dds_write(watch)");
  }
}

void Service::Impl::stop_publisher() {
  if (!publisher || publisher_stopped.exchange(true)) return;
  const UpdatePublisher::Counters c = publisher->shutdown();
  logger()->debug("update publisher stopped: {} published, {} failed, {} merged, {} dropped; peak queue {:.1f} MB",
                  c.published, c.failed, c.taken_back, c.dropped, static_cast<double>(c.max_queued_bytes) / 1e6);
}

}  // namespace surfeledit::service
