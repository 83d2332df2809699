// A ServiceConfig checked against its bounds and turned into the handler's HandlerConfig
// (server/service/src/service_config.hpp).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

#include "../../server/service/src/service_config.hpp"

using namespace surfeledit::service;

namespace {

// A config whose every handler setting differs from both the ServiceConfig's and the HandlerConfig's
// default, so that a setting left out of handler_config shows as its default.
ServiceConfig distinct_config() {
  ServiceConfig c;
  c.max_chunk_surfels = 1000;
  c.max_model_surfels = 123456;
  c.threads = 3;
  c.data_root = "models";
  c.max_file_bytes = 777;
  c.client_lease_ms = 4321;
  c.session_grace_ms = 8765;
  c.max_client_upload_bytes = 11;
  c.max_upload_bytes = 22;
  c.max_reply_cache_bytes = 33;
  c.security = "security.conf";
  c.grants = {Grant{"alice", Role::Editor, "s"}, Grant{"bob", Role::Viewer, ""}};
  return c;
}

// handler_config(c) after `change` throws std::invalid_argument whose message contains `words`.
void expect_refused(const std::function<void(ServiceConfig&)>& change, const std::string& words) {
  ServiceConfig c;
  change(c);
  try {
    handler_config(c);
    ADD_FAILURE() << "accepted; expected a refusal mentioning '" << words << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(ServiceConfig, EveryHandlerSettingIsHandedOver) {
  const ServiceConfig c = distinct_config();
  const HandlerConfig h = handler_config(c);
  EXPECT_EQ(h.max_chunk_surfels, 1000u);
  EXPECT_EQ(h.max_model_surfels, 123456u);
  EXPECT_EQ(h.threads, 3);
  EXPECT_EQ(h.data_root, "models");
  EXPECT_EQ(h.max_file_bytes, 777u);
  EXPECT_EQ(h.client_lease, std::chrono::milliseconds(4321));
  EXPECT_EQ(h.session_grace, std::chrono::milliseconds(8765));
  EXPECT_EQ(h.max_client_upload_bytes, 11u);
  EXPECT_EQ(h.max_upload_bytes, 22u);
  EXPECT_EQ(h.max_reply_cache_bytes, 33u);
  ASSERT_EQ(h.grants.size(), 2u);
  EXPECT_EQ(h.grants[0].user, "alice");
  EXPECT_EQ(h.grants[0].role, Role::Editor);
  EXPECT_EQ(h.grants[0].session, "s");
  EXPECT_EQ(h.grants[1].user, "bob");
  EXPECT_EQ(h.grants[1].role, Role::Viewer);
}

TEST(ServiceConfig, BoundsAreInclusive) {
  ServiceConfig c;
  c.domain = 232;
  c.max_chunk_surfels = std::uint64_t(1) << 24;
  c.max_model_surfels = INT32_MAX;
  c.client_lease_ms = 3'600'000;
  c.session_grace_ms = 86'400'000;
  EXPECT_NO_THROW(handler_config(c));
  c.domain = 0;
  c.max_chunk_surfels = 1;
  c.max_model_surfels = 1;
  c.client_lease_ms = 1;
  c.session_grace_ms = 0;
  EXPECT_NO_THROW(handler_config(c));
}

TEST(ServiceConfig, SettingsOutOfBoundsAreRefusedByName) {
  expect_refused([](ServiceConfig& c) { c.domain = -1; }, "domain");
  expect_refused([](ServiceConfig& c) { c.domain = 233; }, "domain");
  expect_refused([](ServiceConfig& c) { c.max_chunk_surfels = 0; }, "max_chunk_surfels");
  expect_refused([](ServiceConfig& c) { c.max_chunk_surfels = (std::uint64_t(1) << 24) + 1; }, "max_chunk_surfels");
  expect_refused([](ServiceConfig& c) { c.max_model_surfels = 0; }, "max_model_surfels");
  expect_refused([](ServiceConfig& c) { c.max_model_surfels = std::uint64_t(INT32_MAX) + 1; }, "max_model_surfels");
  expect_refused([](ServiceConfig& c) { c.threads = -1; }, "threads");
  expect_refused([](ServiceConfig& c) { c.max_update_queue_bytes = 0; }, "max_update_queue_bytes");
  expect_refused([](ServiceConfig& c) { c.max_file_bytes = 0; }, "max_file_bytes");
  expect_refused([](ServiceConfig& c) { c.client_lease_ms = 0; }, "client_lease_ms");
  expect_refused([](ServiceConfig& c) { c.client_lease_ms = 3'600'001; }, "client_lease_ms");
  expect_refused([](ServiceConfig& c) { c.session_grace_ms = 86'400'001; }, "session_grace_ms");
  expect_refused([](ServiceConfig& c) { c.max_client_upload_bytes = 0; }, "upload");
  expect_refused([](ServiceConfig& c) { c.max_upload_bytes = 0; }, "upload");
  expect_refused([](ServiceConfig& c) { c.max_reply_cache_bytes = 0; }, "reply cache");
}

TEST(ServiceConfig, GrantsNeedSecurityAndNoJournal) {
  expect_refused([](ServiceConfig& c) { c.grants = {Grant{"alice", Role::Editor, ""}}; }, "--security");
  expect_refused(
      [](ServiceConfig& c) {
        c.grants = {Grant{"alice", Role::Editor, ""}};
        c.security = "security.conf";
        c.journal.dir = "journal";
      },
      "--journal");
}
