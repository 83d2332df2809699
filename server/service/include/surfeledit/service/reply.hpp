// The service's own form of a Reply (proto/surfeledit.idl): plain C++ values, so that replies
// can be built, stored in the request cache and compared without touching DDS memory.
// sample_views.hpp presents one as the generated C type for writing.
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
  PermissionDenied = 7,  // the caller's role in the session does not allow the op
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
  std::vector<double> clip_points;   // n*3 clip line points, or empty when the model has no clip lines
  std::vector<double> clip_dirs;     // n*3 unit directions (zero: unclipped), or empty likewise
};

// One named session setting (proto Setting); the value is in the member its kind names.
enum class SettingKind : std::uint32_t { Number = 0, Bool = 1, Text = 2, Int = 3 };
struct Setting {
  std::string name;
  SettingKind kind = SettingKind::Number;
  double number = 0.0;  // Number, Int (integral)
  bool flag = false;    // Bool
  std::string text;     // Text
};

struct SessionInfo {
  std::string name;
  std::uint64_t surfels = 0;
  bool has_regions = false;
  std::uint64_t state_hash = 0;
  std::uint32_t clients = 0;
  double bytes_per_surfel = 0.0;
  std::vector<std::pair<std::string, std::uint64_t>> structures;  // name -> bytes
  std::vector<Setting> settings;  // every setting with its current value
};

struct ServerInfo {
  std::string version;
  double uptime_s = 0.0;
  std::vector<std::string> sessions;  // names, sorted
  std::uint64_t max_chunk_surfels = 0;
  std::uint64_t max_model_surfels = 0;
  std::uint32_t clients = 0;                   // clients known to the server (bound ids)
  std::uint64_t upload_bytes = 0;              // memory of unfinished uploads, all clients
  std::uint64_t client_upload_bytes = 0;       // of those, the caller's
  std::uint64_t max_upload_bytes = 0;          // total upload memory limit
  std::uint64_t max_client_upload_bytes = 0;   // per-client upload memory limit
  std::uint64_t reply_cache_bytes = 0;         // replies kept for repeats (estimated bytes)
  double client_lease_s = 0.0;                 // detach a client whose writer is not alive this long
  double session_grace_s = 0.0;                // keep a session whose last client was detached this long
};

// The collision detector's counters of one step (proto CollisionStats).
struct CollisionStatsInfo {
  std::uint64_t deformable = 0;  // deformable surfels considered
  std::uint64_t tested = 0;      // surfels (re)evaluated this step
  std::uint64_t queries = 0;     // nearest-neighbour queries made this step
  std::uint64_t colliding = 0;   // surfels reported colliding
  double detect_ms = 0.0;        // this step's detection time
  double preprocess_ms = 0.0;    // last (re)initialisation of the detector
  std::uint64_t nv = 0;          // hierarchies: bounding-volume overlap tests this step; 0 without
  std::uint64_t np = 0;          // hierarchies: candidates handed to the narrow phase this step; 0 without
  std::uint64_t nu = 0;          // hierarchies: boxes updated this step (refit, insertion); 0 without
  std::uint64_t asleep = 0;      // deformable surfels of sleeping blocks: not read this step
};

// What one deformation step did (proto StepResult; the core's is surfeledit::StepResult).
struct StepResult {
  std::uint64_t seq = 0;    // 1-based step number in the session
  std::uint64_t moved = 0;  // surfels displaced
  std::array<double, 3> center{};  // rotation centre used, model units
  bool detected = false;             // a collision detector ran
  std::vector<std::uint64_t> colliding;  // colliding ids after the step, ascending
  std::vector<double> depths;            // per colliding id: penetration depth estimate, model units
  CollisionStatsInfo stats;
  std::vector<std::uint64_t> inserted;   // ids inserted by dynamic resampling
  std::string response = "none";         // "none" | "reported" | "cancelled" | "backed_off"
  std::uint32_t backoff_iterations = 0;  // back-off: re-tests made
  double backoff_kept = 1.0;             // back-off: fraction of the requested step kept
  double backoff_depth = 0.0;            // back-off: largest depth after it, model units
  std::vector<std::uint64_t> features;   // merge: feature surfel ids (empty: merge is not offered yet)
};

// One entry of a session's edit history (proto HistoryEntry).
struct HistoryInfo {
  std::uint64_t version = 0;  // session version after the change
  std::string op;             // "load" | "set_regions" | "deform" | "configure" | "remove" | "merge"
  std::string client_id;      // who made it
  std::vector<std::uint64_t> touched;  // ids changed, inserted or removed, ascending
  bool undone = false;        // in the redo tail
};

// An intersection curve (proto Curve).
struct CurveInfo {
  std::vector<double> points;  // k*3, in curve order
  bool closed = false;         // the last point connects back to the first
};

// What OP_MERGE did (proto MergeResult).
struct MergeInfo {
  std::vector<std::uint64_t> removed, features, moved, inserted;  // ids (see EditSession::merge)
  std::vector<CurveInfo> curves;
  double merge_ms = 0.0, crease_ms = 0.0, curves_ms = 0.0;
};

// What OP_BLEND did (proto BlendResult; see EditSession::blend).
struct BlendInfo {
  std::uint32_t particles = 0;
  std::vector<std::uint64_t> moved, inserted, removed;
  std::vector<double> energy;  // per iteration
  std::uint32_t substeps = 0;
  double ms = 0.0;
};

// One filled hole (proto Hole).
struct HoleInfo {
  std::vector<std::uint64_t> boundary;
  double diameter = 0.0;
  std::vector<std::uint64_t> inserted;
};

// What OP_FILL_HOLES did (proto FillResult).
struct FillInfo {
  std::vector<HoleInfo> holes;
  std::uint32_t skipped = 0;
  std::vector<std::uint64_t> inserted;
  double ms = 0.0;
};

// One client of a session (proto Peer; OP_PEERS and presence updates).
struct PeerInfo {
  std::string client_id;
  std::string role;              // "owner" | "editor" | "viewer"
  std::string state;             // "attached" | "lease" (writer gone, lease running) | "away" (detached, in grace)
  std::string last_op;           // its last op that changed the session ("" before any)
  std::uint64_t last_version = 0;  // the version that op produced
  double idle_ms = 0.0;          // since its last request to the session (away: since it was detached)
  std::uint64_t zero = 0;        // its tool: surfels of the zero region
  std::uint64_t one = 0;         // of the one region
  std::uint64_t deformable = 0;  // it may move (s > 0)
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
  std::optional<StepResult> step;
  std::vector<HistoryInfo> history;  // OP_HISTORY
  std::optional<MergeInfo> merge;    // OP_MERGE
  std::vector<CurveInfo> curves;     // OP_CURVES
  std::string token;                 // OP_INVITE: the invitation token
  std::uint32_t request_op = 0;      // the op number of the request answered
  std::optional<BlendInfo> blend;    // OP_BLEND
  std::optional<FillInfo> fill;      // OP_FILL_HOLES
  std::vector<PeerInfo> peers;       // OP_PEERS
  // A reply restored from a journal snapshot (docs/journal.md): the whole reply as the CDR of the IDL
  // Reply, written as it is; the members above then hold only what the cache and journal read (ids, op,
  // status, field, message, version, token). Empty for a reply built here.
  std::vector<std::uint8_t> wire;
};

}  // namespace surfeledit::service
