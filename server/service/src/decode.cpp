#include "surfeledit/service/decode.hpp"

#include <cmath>
#include <optional>
#include <type_traits>

#include "surfeledit/service/protocol_errors.hpp"

namespace surfeledit::service {

namespace {

// The project's op numbers are the protocol's.
static_assert(static_cast<std::uint32_t>(Op::Info) == surfeledit_proto_OP_INFO, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::OpenSession) == surfeledit_proto_OP_OPEN_SESSION, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::JoinSession) == surfeledit_proto_OP_JOIN_SESSION, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::CloseSession) == surfeledit_proto_OP_CLOSE_SESSION, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::LoadBegin) == surfeledit_proto_OP_LOAD_BEGIN, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::LoadChunk) == surfeledit_proto_OP_LOAD_CHUNK, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::LoadCommit) == surfeledit_proto_OP_LOAD_COMMIT, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::LoadFile) == surfeledit_proto_OP_LOAD_FILE, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::SetRegions) == surfeledit_proto_OP_SET_REGIONS, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Deform) == surfeledit_proto_OP_DEFORM, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::GetState) == surfeledit_proto_OP_GET_STATE, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Configure) == surfeledit_proto_OP_CONFIGURE, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Remove) == surfeledit_proto_OP_REMOVE, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Undo) == surfeledit_proto_OP_UNDO, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Redo) == surfeledit_proto_OP_REDO, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::History) == surfeledit_proto_OP_HISTORY, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Merge) == surfeledit_proto_OP_MERGE, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Curves) == surfeledit_proto_OP_CURVES, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Invite) == surfeledit_proto_OP_INVITE, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Blend) == surfeledit_proto_OP_BLEND, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Boolean) == surfeledit_proto_OP_BOOLEAN, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::FillHoles) == surfeledit_proto_OP_FILL_HOLES, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Peers) == surfeledit_proto_OP_PEERS, "Op numbers");
static_assert(static_cast<std::uint32_t>(Op::Release) == surfeledit_proto_OP_RELEASE, "Op numbers");
static_assert(kOpCount == surfeledit_proto_OP_RELEASE + 1, "kOpCount: one past the last proto Op");

// The one element of an op's argument sequence; InvalidArgument naming the sequence otherwise.
template <typename Seq>
const auto& the_argument(const Seq& seq, const char* name) {
  if (seq._length != 1 || seq._buffer == nullptr) {
    throw Error(ErrorCode::InvalidArgument, name,
                std::string("expected exactly one element, got ") + std::to_string(seq._length));
  }
  return seq._buffer[0];
}

// Decodes the op's argument sequence `seq` (named `name`) with `decode_one`: a missing argument
// goes to c.missing, a failed decoding to c.invalid.
template <typename Seq, typename F>
void decode_argument(Command& c, const Seq& seq, const char* name, F&& decode_one) {
  const std::remove_pointer_t<decltype(seq._buffer)>* arg = nullptr;
  try {
    arg = &the_argument(seq, name);
  } catch (...) {
    c.missing = std::current_exception();
    return;
  }
  try {
    c.args = decode_one(*arg);
  } catch (...) {
    c.invalid = std::current_exception();
  }
}

}  // namespace

std::string str(const char* s) { return s ? std::string(s) : std::string(); }

Vec3 to_core(const surfeledit_proto_Vec3& v) { return Vec3(v.x, v.y, v.z); }

surfeledit_proto_Vec3 to_proto(const Vec3& v) { return surfeledit_proto_Vec3{v.x(), v.y(), v.z()}; }

Selector to_core(const surfeledit_proto_Selector& s, const std::string& field) {
  Selector out;
  switch (s.kind) {
    case surfeledit_proto_SELECTOR_SPHERE: out.kind = Selector::Kind::Sphere; break;
    case surfeledit_proto_SELECTOR_BOX: out.kind = Selector::Kind::Box; break;
    default:
      throw Error(ErrorCode::InvalidArgument, field + ".kind",
                  "unknown selector kind " + std::to_string(static_cast<long>(s.kind)));
  }
  out.center = to_core(s.center);
  out.radius = s.radius;
  out.half_extents = to_core(s.half_extents);
  validate(out, field);
  return out;
}

RegionSpec to_core(const surfeledit_proto_RegionSpec& r, const std::string& field) {
  RegionSpec out;
  if (r.ids._length > 0) out.ids.assign(r.ids._buffer, r.ids._buffer + r.ids._length);
  out.selectors.reserve(r.selectors._length);
  for (uint32_t i = 0; i < r.selectors._length; ++i) {
    out.selectors.push_back(to_core(r.selectors._buffer[i], field + ".selectors[" + std::to_string(i) + "]"));
  }
  return out;
}

DeformParams to_core(const surfeledit_proto_Deform& d, const std::string& field) {
  DeformParams out;
  out.translation = to_core(d.translation);
  out.axis = to_core(d.axis);
  out.angle = d.angle;
  if (d.has_center) out.center = to_core(d.center);
  const std::string blend = str(d.blend);
  out.blend = blend.empty() ? Blend::Smooth : parse_blend(blend, field + ".blend");
  try {
    validate(out);
  } catch (const Error& e) {
    rethrow_prefixed(e, field);
  }
  return out;
}

namespace {

// A SETTING_INT value: the integer when `number` is integral and fits, else the number itself (the core
// then refuses it naming the setting, as it refuses 2.5 for an integer setting).
SettingValue integral_or_number(double number) {
  const bool integral = std::isfinite(number) && number == std::floor(number) && std::abs(number) < 0x1p63;
  return integral ? SettingValue(static_cast<std::int64_t>(number)) : SettingValue(number);
}

}  // namespace

std::vector<NamedSetting> to_core(const surfeledit_proto_Configure& c, const std::string& field) {
  std::vector<NamedSetting> out;
  out.reserve(c.settings._length);
  for (uint32_t i = 0; i < c.settings._length; ++i) {
    const surfeledit_proto_Setting& s = c.settings._buffer[i];
    NamedSetting named;
    named.name = str(s.name);
    if (named.name.empty()) {  // found by the request fuzzer: the error named no field
      throw Error(ErrorCode::InvalidArgument, field + ".settings[" + std::to_string(i) + "].name",
                  "a setting name is required");
    }
    switch (s.kind) {
      case surfeledit_proto_SETTING_NUMBER: named.value = s.number; break;
      case surfeledit_proto_SETTING_INT: named.value = integral_or_number(s.number); break;
      case surfeledit_proto_SETTING_BOOL: named.value = static_cast<bool>(s.flag); break;
      case surfeledit_proto_SETTING_TEXT: named.value = str(s.text); break;
      default:
        throw Error(ErrorCode::InvalidArgument,
                    named.name.empty() ? field + ".settings[" + std::to_string(i) + "]" : named.name,
                    "unknown setting kind " + std::to_string(static_cast<long>(s.kind)));
    }
    out.push_back(std::move(named));
  }
  return out;
}

Command decode(const surfeledit_proto_Request& r) {
  Command c;
  c.client_id = str(r.client_id);
  c.request_id = r.request_id;
  c.session = str(r.session);
  c.op = static_cast<Op>(r.op);
  c.token = str(r.token);
  if (r.expect_version._length == 1 && r.expect_version._buffer) {
    c.expect_version = r.expect_version._buffer[0];
  } else if (r.expect_version._length > 1) {
    c.invalid = std::make_exception_ptr(Error(ErrorCode::InvalidArgument, "expect_version",
                                              "expected 0 or 1 element, got " +
                                                  std::to_string(r.expect_version._length)));
  }
  switch (c.op) {
    case Op::LoadBegin:
      decode_argument(c, r.load_begin, "load_begin", [](const surfeledit_proto_LoadBegin& a) {
        return LoadBeginArgs{a.total, a.has_radii};
      });
      break;
    case Op::LoadChunk:
      decode_argument(c, r.load_chunk, "load_chunk", [](const surfeledit_proto_LoadChunk& a) {
        ChunkData chunk;
        chunk.offset = a.offset;
        chunk.positions = a.positions._buffer;
        chunk.positions_len = a.positions._length;
        chunk.normals = a.normals._buffer;
        chunk.normals_len = a.normals._length;
        chunk.radii = a.radii._buffer;
        chunk.radii_len = a.radii._length;
        return chunk;
      });
      break;
    case Op::LoadFile:
      decode_argument(c, r.load_file, "load_file", [](const surfeledit_proto_LoadFile& a) {
        LoadFileArgs args{str(a.path)};
        if (args.path.empty()) throw Error(ErrorCode::InvalidArgument, "load_file.path", "a file path is required");
        return args;
      });
      break;
    case Op::SetRegions:
      decode_argument(c, r.set_regions, "set_regions", [](const surfeledit_proto_SetRegions& a) {
        SetRegionsArgs args;
        args.zero = to_core(a.zero, "set_regions.zero");
        args.one = to_core(a.one, "set_regions.one");
        return args;
      });
      break;
    case Op::Deform:
      decode_argument(c, r.deform, "deform", [](const surfeledit_proto_Deform& a) { return to_core(a, "deform"); });
      break;
    case Op::GetState:
      decode_argument(c, r.get_state, "get_state", [](const surfeledit_proto_GetState& a) {
        return GetStateArgs{static_cast<bool>(a.changes_only), a.since_version, a.offset, a.max_count};
      });
      break;
    case Op::Configure:
      decode_argument(c, r.configure, "configure",
                      [](const surfeledit_proto_Configure& a) { return ConfigureArgs{to_core(a, "configure")}; });
      break;
    case Op::Remove:
      decode_argument(c, r.remove, "remove", [](const surfeledit_proto_Remove& a) {
        RemoveArgs args;
        if (a.ids._length > 0) args.ids.assign(a.ids._buffer, a.ids._buffer + a.ids._length);
        return args;
      });
      break;
    case Op::Merge:
      decode_argument(c, r.merge, "merge", [](const surfeledit_proto_Merge& a) {
        return MergeArgs{static_cast<bool>(a.crease)};
      });
      break;
    case Op::Curves:
      decode_argument(c, r.curves, "curves",
                      [](const surfeledit_proto_Curves& a) { return CurvesArgs{a.refine_angle}; });
      break;
    case Op::Invite:
      decode_argument(c, r.invite, "invite", [](const surfeledit_proto_Invite& a) {
        const std::string name = str(a.role);
        const std::optional<Role> role = invitable_role(name);
        if (!role) {
          throw Error(ErrorCode::InvalidArgument, "invite.role", "role '" + name + "': expected 'editor' or 'viewer'");
        }
        return InviteArgs{*role};
      });
      break;
    case Op::Blend:
      decode_argument(c, r.blend, "blend", [](const surfeledit_proto_Blend& a) {
        BlendArgs args;
        args.params.iterations = a.iterations;
        args.params.range_factor = a.range_factor;
        args.params.dt = a.dt;
        args.params.only_grow = a.only_grow;
        args.params.adaptive = a.adaptive;
        args.repulsion = str(a.repulsion);
        args.weight = str(a.weight);
        args.neighbourhood = str(a.neighbourhood);
        args.projection = str(a.projection);
        if (a.has_features) args.features = IdList(a.features._buffer, a.features._buffer + a.features._length);
        return args;
      });
      break;
    case Op::Boolean:
      decode_argument(c, r.boolean_op, "boolean_op",
                      [](const surfeledit_proto_BooleanOperation& a) { return BooleanArgs{str(a.op)}; });
      break;
    case Op::FillHoles:
      decode_argument(c, r.fill_holes, "fill_holes", [](const surfeledit_proto_FillHoles& a) {
        FillHolesArgs args;
        args.params.max_diameter = a.max_diameter;
        args.params.iterations = a.iterations;
        args.projection = str(a.projection);
        if (a.has_boundary) args.boundary = IdList(a.boundary._buffer, a.boundary._buffer + a.boundary._length);
        return args;
      });
      break;
    default: break;  // no argument (or an op outside the list, rejected by the handler)
  }
  return c;
}

}  // namespace surfeledit::service
