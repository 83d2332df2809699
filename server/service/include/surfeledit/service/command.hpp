// A request as the handler sees it: the header of a proto Request and its op's argument as project
// types, decoded and validated by decode.hpp's decode(). One argument struct per op that has one;
// adding an op is its IDL argument, its decoding and one handler function (handler_ops.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/types.hpp"
#include "surfeledit/service/access.hpp"
#include "surfeledit/service/upload.hpp"

namespace surfeledit::service {

// Protocol op numbers (proto Op, same values). A received value may lie outside the list.
enum class Op : std::uint32_t {
  Info = 0,
  OpenSession = 1,
  JoinSession = 2,
  CloseSession = 3,
  LoadBegin = 4,
  LoadChunk = 5,
  LoadCommit = 6,
  LoadFile = 7,
  SetRegions = 8,
  Deform = 9,
  GetState = 10,
  Configure = 11,
  Remove = 12,
  Undo = 13,
  Redo = 14,
  History = 15,
  Merge = 16,
  Curves = 17,
  Invite = 18,
  Blend = 19,
  Boolean = 20,
  FillHoles = 21,
  Peers = FillHoles + 1,  // the IDL's ops after FillHoles (numbered there; decode.cpp checks them)
  Release = Peers + 1,
};
constexpr std::size_t kOpCount = static_cast<std::size_t>(Op::Release) + 1;  // ops 0 .. kOpCount-1

// OP_LOAD_BEGIN: an inline upload of `total` surfels follows.
struct LoadBeginArgs {
  std::uint64_t total = 0;  // surfels to come
  bool has_radii = false;   // false: radii are estimated from spacing
};

// OP_LOAD_FILE: a file on the server's file system.
struct LoadFileArgs {
  std::string path;  // not empty
};

// OP_SET_REGIONS: validated selectors.
struct SetRegionsArgs {
  RegionSpec zero;
  RegionSpec one;
};

// OP_GET_STATE: what to fetch and which page of it.
struct GetStateArgs {
  bool changes_only = false;        // false: everything; true: what changed since `since_version`
  std::uint64_t since_version = 0;
  std::uint64_t offset = 0;         // into the answer's ascending ids
  std::uint64_t max_count = 0;      // 0: the server's page limit
};

// OP_CONFIGURE: settings applied together or not at all (names and values checked by the core).
struct ConfigureArgs {
  std::vector<NamedSetting> settings;
};

// OP_REMOVE: surfels to remove.
struct RemoveArgs {
  IdList ids;
};

// OP_MERGE: merge the regions now.
struct MergeArgs {
  bool crease = true;  // move the feature surfels onto the intersection and clip them
};

// OP_CURVES: intersection curves of the last merge.
struct CurvesArgs {
  double refine_angle = 0.5;  // radians: an edge bending more than this is split (validated by the core)
};

// OP_INVITE: the role the invitation grants.
struct InviteArgs {
  Role role = Role::Viewer;  // Editor or Viewer
};

// OP_BLEND: the blend tool (enum names parsed by the op, naming the blend.* field).
struct BlendArgs {
  BlendParams params;                  // iterations, range_factor, dt, only_grow, adaptive
  std::string repulsion = "weight";    // RepulsionKind name
  std::string weight = "compact";      // WeightKind name
  std::string neighbourhood = "cached";  // NeighbourMode name
  std::string projection = "mls";      // ProjectionKind name
  std::optional<IdList> features;      // none: the last merge's / boolean's features
};

// OP_BOOLEAN: B is the client's completed upload.
struct BooleanArgs {
  std::string op;  // BooleanOp name
};

// OP_FILL_HOLES.
struct FillHolesArgs {
  HoleParams params;                // max_diameter, iterations
  std::optional<IdList> boundary;   // none: detected
  std::string projection = "mls";   // ProjectionKind name
};

// The op's argument: none (std::monostate), or the struct of that op. OP_LOAD_CHUNK's is a
// ChunkData pointing into the received sample, which must outlive the Command; OP_DEFORM's is
// the validated DeformParams.
using OpArguments = std::variant<std::monostate, LoadBeginArgs, ChunkData, LoadFileArgs, SetRegionsArgs,
                                 DeformParams, GetStateArgs, ConfigureArgs, RemoveArgs, MergeArgs, CurvesArgs,
                                 InviteArgs, BlendArgs, BooleanArgs, FillHolesArgs>;

struct Command {
  std::string client_id;       // empty: rejected by the handler (field "client_id")
  std::uint64_t request_id = 0;
  std::string session;         // may be empty for OP_INFO
  Op op = Op::Info;            // possibly a value outside the list (rejected, field "op")
  OpArguments args;            // meaningful only when neither error below is set
  // The argument is absent or not exactly one element: reported before the session is checked.
  std::exception_ptr missing;
  // The argument is present but invalid: reported after the session is checked (so that an
  // unattached client hears about the session first).
  std::exception_ptr invalid;
  std::string token;           // OP_JOIN_SESSION: invitation token (empty: members only)
  // Optimistic concurrency: an op needing the editor role runs only when the session is at this version
  // (Conflict, field "expect_version", otherwise); none: no condition.
  std::optional<std::uint64_t> expect_version;
  // The DDS writer that sent the request (its publication handle); 0: not from DDS (tests, in-process),
  // then the client id is not bound to a sender.
  std::uint64_t sender = 0;
  // The authenticated user that sent it (DDS Security on: the user of the request partition
  // "surfeledit.req.<user>" its writer uses, which only that identity may write in); empty: unknown.
  std::string subject;
};

}  // namespace surfeledit::service
