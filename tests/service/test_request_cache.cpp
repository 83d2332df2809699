// RequestCache: stored replies per client, bounded, least recently active client forgotten first.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "service_test_support.hpp"
#include "surfeledit/service/request_cache.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

namespace {

std::shared_ptr<const Reply> reply_for(const std::string& client, std::uint64_t id, const std::string& message = "") {
  auto r = std::make_shared<Reply>();
  r->client_id = client;
  r->request_id = id;
  r->message = message;
  return r;
}

}  // namespace

TEST(RequestCache, StoresAndFindsPerClient) {
  RequestCache cache;
  cache.put(reply_for("a", 1, "a1"));
  cache.put(reply_for("b", 1, "b1"));
  ASSERT_NE(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.find("a", 1)->message, "a1");
  EXPECT_EQ(cache.find("b", 1)->message, "b1");
  EXPECT_EQ(cache.find("a", 2), nullptr);
  EXPECT_EQ(cache.find("c", 1), nullptr);
  EXPECT_EQ(cache.clients(), 2u);
}

TEST(RequestCache, KeepsTheLast1024RepliesPerClient) {
  RequestCache cache;
  for (std::uint64_t id = 1; id <= 1500; ++id) cache.put(reply_for("a", id));
  EXPECT_EQ(cache.size("a"), 1024u);
  EXPECT_EQ(cache.find("a", 476), nullptr);  // 1500 - 1024 = 476 evicted
  EXPECT_NE(cache.find("a", 477), nullptr);
  EXPECT_NE(cache.find("a", 1500), nullptr);
}

TEST(RequestCache, AHitRefreshesRecency) {
  RequestCache cache(3);
  cache.put(reply_for("a", 1));
  cache.put(reply_for("a", 2));
  cache.put(reply_for("a", 3));
  ASSERT_NE(cache.find("a", 1), nullptr);  // 1 is now the most recent
  cache.put(reply_for("a", 4));            // evicts 2
  EXPECT_NE(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.find("a", 2), nullptr);
  EXPECT_NE(cache.find("a", 3), nullptr);
  EXPECT_NE(cache.find("a", 4), nullptr);
}

TEST(RequestCache, ForgetsTheLeastRecentlyActiveClient) {
  RequestCache cache(4, 2);
  cache.put(reply_for("a", 1));
  cache.put(reply_for("b", 1));
  ASSERT_NE(cache.find("a", 1), nullptr);  // a active again
  cache.put(reply_for("c", 1));            // b is forgotten
  EXPECT_NE(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.find("b", 1), nullptr);
  EXPECT_NE(cache.find("c", 1), nullptr);
  cache.forget("a");
  EXPECT_EQ(cache.find("a", 1), nullptr);
  EXPECT_EQ(cache.clients(), 1u);
}

TEST(RequestCache, PutReplacesTheSameId) {
  RequestCache cache;
  cache.put(reply_for("a", 7, "old"));
  cache.put(reply_for("a", 7, "new"));
  EXPECT_EQ(cache.size("a"), 1u);
  EXPECT_EQ(cache.find("a", 7)->message, "new");
}

TEST(RequestCache, IsBoundedInBytesAcrossClients) {
  const std::size_t one = reply_bytes(*reply_for("a", 1));
  RequestCache cache(RequestCacheLimits{1024, 4096, 3 * one});
  cache.put(reply_for("a", 1));
  cache.put(reply_for("b", 1));
  cache.put(reply_for("a", 2));
  EXPECT_EQ(cache.bytes(), 3 * one);
  cache.put(reply_for("c", 1));  // evicts the least recently used reply of any client: a#1
  EXPECT_EQ(cache.bytes(), 3 * one);
  EXPECT_EQ(cache.find("a", 1), nullptr);
  EXPECT_NE(cache.find("b", 1), nullptr);
  auto big = std::make_shared<Reply>();
  big->client_id = "d";
  big->request_id = 1;
  big->message.assign(4 * one, 'x');
  cache.put(big);  // larger than the bound: not stored, nothing else evicted
  EXPECT_EQ(cache.find("d", 1), nullptr);
  EXPECT_EQ(cache.bytes(), 3 * one);
  cache.forget("b");
  EXPECT_EQ(cache.bytes(), 2 * one);
}
