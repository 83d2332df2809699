// The service's own form of a Reply (proto/surfeledit.idl): plain C++ values, so that replies
// can be built, stored in the request cache and compared without touching DDS memory.
// convert.hpp turns one into the generated C type for writing.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace surfeledit::service {

// Protocol status numbers (proto Status): 0 = OK, otherwise the core's ErrorCode number.
enum class Status : std::uint32_t {
  Ok = 0,
  InvalidArgument = 1,
  NotFound = 2,
  Conflict = 3,
  TooLarge = 4,
  Io = 5,
  Internal = 6,
};

// One page of GET_STATE: ids ascending with their attributes.
struct StatePage {
  bool full = false;                 // the answer is the whole model
  std::uint64_t total = 0;           // ids in the whole answer (all pages)
  std::uint64_t offset = 0;          // of this page
  std::vector<std::uint64_t> ids;    // n
  std::vector<double> positions;     // n*3, row-major
  std::vector<double> normals;       // n*3, row-major
  std::vector<double> radii;         // n
  std::vector<std::uint64_t> removed;  // removed ids (first page only)
};

struct SessionInfo {
  std::string name;
  std::uint64_t surfels = 0;
  bool has_regions = false;
  std::uint64_t state_hash = 0;
  std::uint32_t clients = 0;
  double bytes_per_surfel = 0.0;
  std::vector<std::pair<std::string, std::uint64_t>> structures;  // name -> bytes
};

struct ServerInfo {
  std::string version;
  double uptime_s = 0.0;
  std::vector<std::string> sessions;  // names, sorted
  std::uint64_t max_chunk_surfels = 0;
  std::uint64_t max_model_surfels = 0;
};

struct StepInfo {
  std::uint64_t seq = 0;    // 1-based step number in the session
  std::uint64_t moved = 0;  // surfels displaced
  std::array<double, 3> center{};  // rotation centre used, model units
};

struct Reply {
  std::string client_id;
  std::uint64_t request_id = 0;
  Status status = Status::Ok;
  std::string field;    // offending input when status != Ok
  std::string message;
  std::uint64_t version = 0;  // session version after the request (0 without session)
  std::vector<std::pair<std::string, double>> timings;  // name -> milliseconds
  std::optional<StatePage> state;
  std::optional<SessionInfo> session_info;
  std::optional<ServerInfo> server_info;
  std::optional<StepInfo> step;
};

}  // namespace surfeledit::service
