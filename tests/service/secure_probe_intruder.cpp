// surfeledit-secure-probe: the intruder (`intruder`), which tries to read and write a session's data.
#include <unistd.h>

#include <cstdio>
#include <thread>

#include "secure_probe.hpp"

namespace surfeledit::probe {

int run_intruder(const Args& a) {
  const dds_entity_t pp = make_participant(a.domain, a.security);
  if (pp < 0) {
    std::printf("participant=%s\nwritten=0\nmatched_servers=0\nreplies_read=0\nupdates_read=0\n", dds_strretcode(pp));
    return 0;
  }
  std::printf("participant=created\n");
  const dds_entity_t req_t = dds_create_topic(pp, &kRequestDesc, "surfeledit_request", nullptr, nullptr);
  const dds_entity_t rep_t = dds_create_topic(pp, &kReplyDesc, "surfeledit_reply", nullptr, nullptr);
  const dds_entity_t upd_t = dds_create_topic(pp, &kUpdateDesc, "surfeledit_update", nullptr, nullptr);
  std::printf("topics=%s\n", req_t < 0 || rep_t < 0 || upd_t < 0 ? "refused" : "created");
  dds_entity_t writer = -1;
  if (req_t > 0) {
    dds_qos_t* wq = protocol_qos(false, true);
    writer = dds_create_writer(pp, req_t, wq, nullptr);
    dds_delete_qos(wq);
  }
  std::printf("writer=%s\n", writer > 0 ? "created" : writer < 0 && req_t > 0 ? dds_strretcode(writer) : "no topic");
  std::vector<dds_entity_t> reply_readers;
  dds_entity_t updates = -1;
  const std::string self = "intruder-" + std::to_string(::getpid());
  if (rep_t > 0) {
    for (const std::string& id : {a.victim, self}) {
      const dds_entity_t r = make_reader(pp, rep_t, reply_partition(id), true);
      if (r > 0) reply_readers.push_back(r);
    }
  }
  if (upd_t > 0) updates = make_reader(pp, upd_t, "", false);
  std::printf("readers=%zu\n", reply_readers.size() + (updates > 0 ? 1 : 0));
  int written = 0, replies = 0, update_count = 0;
  std::uint32_t matched = 0;
  std::uint64_t next = 1;
  const auto end = Clock::now() + std::chrono::duration<double>(a.seconds);
  while (Clock::now() < end) {
    if (writer > 0) {
      for (const std::string& id : {a.victim, self}) {
        auto r = blank_request(id, next, a.session, surfeledit_proto_OP_OPEN_SESSION);
        if (dds_write(writer, &r) >= 0) ++written;
      }
      ++next;
      dds_publication_matched_status_t pm;
      if (dds_get_publication_matched_status(writer, &pm) >= 0 && pm.total_count > matched) matched = pm.total_count;
    }
    for (const dds_entity_t r : reply_readers) replies += drain<surfeledit_proto_Reply>(r);
    if (updates > 0) {
      update_count += drain<surfeledit_proto_Update>(updates);
      dds_subscription_matched_status_t sm;
      if (dds_get_subscription_matched_status(updates, &sm) >= 0 && sm.total_count > matched) matched = sm.total_count;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::printf("written=%d\nmatched_servers=%u\nreplies_read=%d\nupdates_read=%d\n", written, matched, replies,
              update_count);
  dds_delete(pp);
  return 0;
}

}  // namespace surfeledit::probe
