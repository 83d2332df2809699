#include "service_config.hpp"

#include <chrono>
#include <cstdint>
#include <stdexcept>

namespace surfeledit::service {

HandlerConfig handler_config(const ServiceConfig& c) {
  if (c.domain < 0 || c.domain > 232) throw std::invalid_argument("domain must be in 0..232");
  if (c.max_chunk_surfels == 0) throw std::invalid_argument("max_chunk_surfels must be positive");
  if (c.max_chunk_surfels > (std::uint64_t(1) << 24)) {
    throw std::invalid_argument("max_chunk_surfels must be at most 16777216 (sample size)");
  }
  if (c.max_model_surfels == 0) throw std::invalid_argument("max_model_surfels must be positive");
  if (c.max_model_surfels > std::uint64_t(INT32_MAX)) {
    throw std::invalid_argument("max_model_surfels must be at most 2147483647 (row index range)");
  }
  if (c.threads < 0) throw std::invalid_argument("threads must be >= 0");
  if (c.max_update_queue_bytes == 0) throw std::invalid_argument("max_update_queue_bytes must be positive");
  if (c.max_file_bytes == 0) throw std::invalid_argument("max_file_bytes must be positive");
  if (c.client_lease_ms == 0 || c.client_lease_ms > 3'600'000) {
    throw std::invalid_argument("client_lease_ms must be in 1..3600000");
  }
  if (c.session_grace_ms > 86'400'000) throw std::invalid_argument("session_grace_ms must be in 0..86400000");
  if (c.max_client_upload_bytes == 0 || c.max_upload_bytes == 0 || c.max_reply_cache_bytes == 0) {
    throw std::invalid_argument("upload and reply cache limits must be positive");
  }
  if (!c.grants.empty() && c.security.empty()) {
    throw std::invalid_argument("--grant needs --security (without it a request partition proves no identity)");
  }
  if (!c.grants.empty() && !c.journal.dir.empty()) {
    throw std::invalid_argument("--grant cannot be combined with --journal yet (a granted join would not replay)");
  }
  HandlerConfig h;
  h.max_chunk_surfels = c.max_chunk_surfels;
  h.max_model_surfels = c.max_model_surfels;
  h.threads = c.threads;
  h.data_root = c.data_root;
  h.max_file_bytes = c.max_file_bytes;
  h.grants = c.grants;
  h.max_client_upload_bytes = c.max_client_upload_bytes;
  h.max_upload_bytes = c.max_upload_bytes;
  h.max_reply_cache_bytes = c.max_reply_cache_bytes;
  h.client_lease = std::chrono::milliseconds(c.client_lease_ms);
  h.session_grace = std::chrono::milliseconds(c.session_grace_ms);
  return h;
}

}  // namespace surfeledit::service
