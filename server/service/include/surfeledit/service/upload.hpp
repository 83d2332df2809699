// Inline model upload: LOAD_BEGIN announces `total` surfels, LOAD_CHUNKs arrive in order
// (each at offset == surfels received so far), LOAD_COMMIT hands the arrays to the core.
// One upload per (client, session); chunks are validated before anything is stored. Memory is
// reserved as chunks arrive (not at LOAD_BEGIN) and counted against a per-client and a total limit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit::service {

struct UploadLimits {
  std::uint64_t max_chunk_surfels = 65536;       // per chunk
  std::uint64_t max_model_surfels = 20'000'000;  // per upload (total)
  std::uint64_t max_client_bytes = std::uint64_t(1200) << 20;  // memory of one client's unfinished uploads
  std::uint64_t max_total_bytes = std::uint64_t(4096) << 20;   // memory of all unfinished uploads
};

// One chunk as received: flattened row-major arrays (lengths in doubles).
struct ChunkData {
  std::uint64_t offset = 0;            // index of the chunk's first surfel
  const double* positions = nullptr;   // n*3
  std::size_t positions_len = 0;
  const double* normals = nullptr;     // n*3
  std::size_t normals_len = 0;
  const double* radii = nullptr;       // n, or 0 when the upload has no radii
  std::size_t radii_len = 0;
};

class Upload {
 public:
  // Throws Error: InvalidArgument (total == 0, field "load_begin.total"), TooLarge (total
  // beyond the limit). Reserves nothing yet.
  Upload(std::uint64_t total, bool has_radii, const UploadLimits& limits);

  // Validates the chunk (sizes, offset, finite values, non-zero normals, positive radii) and
  // stores it; throws Error naming the load_chunk field and stores nothing on failure.
  // `max_bytes`: the most bytes() may grow to (the caller's memory budget); TooLarge beyond it.
  void add_chunk(const ChunkData& chunk, std::uint64_t max_bytes = UINT64_MAX);

  // Memory reserved for the arrays so far, bytes.
  std::uint64_t bytes() const;

  std::uint64_t total() const { return total_; }
  std::uint64_t received() const { return received_; }
  bool has_radii() const { return has_radii_; }
  bool complete() const { return received_ == total_; }
  // A copy of the received surfels as arrays (#received() rows).
  SurfelArrays arrays() const;
  // The arrays, the upload's memory released; throws Error(Conflict) unless complete().
  SurfelArrays take();

 private:
  std::uint64_t total_;
  bool has_radii_;
  UploadLimits limits_;
  std::uint64_t received_ = 0;
  // Received rows, flattened row-major (positions, normals n*3; radii n); capacity grows
  // geometrically up to the announced total as chunks arrive.
  std::vector<double> positions_, normals_, radii_;
};

// The uploads in progress, by (client id, session name).
class UploadTable {
 public:
  explicit UploadTable(UploadLimits limits) : limits_(limits) {}
  // Starts (or restarts) the client's upload into the session.
  Upload& begin(const std::string& client, const std::string& session, std::uint64_t total, bool has_radii);
  // The upload in progress, or nullptr.
  Upload* find(const std::string& client, const std::string& session);
  // Adds a chunk to the client's upload within the memory limits (TooLarge, field "load_chunk",
  // naming the limit, when it would exceed one); Conflict (field `field`) without an upload.
  void add_chunk(const std::string& client, const std::string& session, const ChunkData& chunk);
  void erase(const std::string& client, const std::string& session);
  // Drops every upload into the session (when it is dropped).
  void erase_session(const std::string& session);
  // Drops every upload of the client (when it is detached).
  void erase_client(const std::string& client);
  std::size_t size() const { return uploads_.size(); }
  // Memory of unfinished uploads, bytes: all of them, one client's.
  std::uint64_t bytes() const { return total_bytes_; }
  std::uint64_t client_bytes(const std::string& client) const;
  const UploadLimits& limits() const { return limits_; }

 private:
  using Key = std::pair<std::string, std::string>;  // client, session
  void erase(std::map<Key, Upload>::iterator it);

  UploadLimits limits_;
  std::map<Key, Upload> uploads_;
  std::map<std::string, std::uint64_t> client_bytes_;
  std::uint64_t total_bytes_ = 0;
};

}  // namespace surfeledit::service
