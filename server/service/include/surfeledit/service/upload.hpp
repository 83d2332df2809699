// Inline model upload: LOAD_BEGIN announces `total` surfels, LOAD_CHUNKs arrive in order
// (each at offset == surfels received so far), LOAD_COMMIT hands the arrays to the core.
// One upload per (client, session); chunks are validated before anything is stored.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit::service {

struct UploadLimits {
  std::uint64_t max_chunk_surfels = 65536;       // per chunk
  std::uint64_t max_model_surfels = 20'000'000;  // per upload (total)
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
  // beyond the limit); std::bad_alloc when the arrays cannot be reserved.
  Upload(std::uint64_t total, bool has_radii, const UploadLimits& limits);

  // Validates the chunk (sizes, offset, finite values, non-zero normals, positive radii) and
  // stores it; throws Error naming the load_chunk field and stores nothing on failure.
  void add_chunk(const ChunkData& chunk);

  std::uint64_t total() const { return total_; }
  std::uint64_t received() const { return received_; }
  bool has_radii() const { return has_radii_; }
  bool complete() const { return received_ == total_; }
  // The arrays (#total rows; rows >= received() are not yet filled).
  const SurfelArrays& arrays() const { return arrays_; }
  // Moves the arrays out; throws Error(Conflict) unless complete().
  SurfelArrays take();

 private:
  std::uint64_t total_;
  bool has_radii_;
  UploadLimits limits_;
  std::uint64_t received_ = 0;
  SurfelArrays arrays_;
};

// The uploads in progress, by (client id, session name).
class UploadTable {
 public:
  explicit UploadTable(UploadLimits limits) : limits_(limits) {}
  // Starts (or restarts) the client's upload into the session.
  Upload& begin(const std::string& client, const std::string& session, std::uint64_t total, bool has_radii);
  // The upload in progress, or nullptr.
  Upload* find(const std::string& client, const std::string& session);
  void erase(const std::string& client, const std::string& session);
  // Drops every upload into the session (when it is dropped).
  void erase_session(const std::string& session);
  std::size_t size() const { return uploads_.size(); }

 private:
  UploadLimits limits_;
  std::map<std::pair<std::string, std::string>, Upload> uploads_;
};

}  // namespace surfeledit::service
