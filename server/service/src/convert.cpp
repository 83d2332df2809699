#include "surfeledit/service/convert.hpp"

#include <cmath>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <variant>

namespace surfeledit::service {

namespace {

// A non-owning C sequence over a vector's storage (the writer only reads it).
template <typename Seq, typename T>
Seq borrow(const std::vector<T>& v) {
  Seq s{};
  s._maximum = static_cast<uint32_t>(v.size());
  s._length = static_cast<uint32_t>(v.size());
  s._buffer = v.empty() ? nullptr : const_cast<T*>(v.data());
  s._release = false;
  return s;
}

template <typename Seq, typename T>
Seq borrow_one(T* element, bool present) {
  Seq s{};
  s._maximum = present ? 1 : 0;
  s._length = present ? 1 : 0;
  s._buffer = present ? element : nullptr;
  s._release = false;
  return s;
}

// A non-owning C sequence over `count` elements at `data`.
template <typename Seq, typename T>
Seq borrow_range(const T* data, std::size_t count) {
  Seq s{};
  s._maximum = static_cast<uint32_t>(count);
  s._length = static_cast<uint32_t>(count);
  s._buffer = count == 0 ? nullptr : const_cast<T*>(data);
  s._release = false;
  return s;
}

char* cstr(const std::string& s) { return const_cast<char*>(s.c_str()); }

// Wire views of peers (strings borrowed from `peers`, which must outlive them).
std::vector<surfeledit_proto_Peer> peer_views(const std::vector<PeerInfo>& peers) {
  std::vector<surfeledit_proto_Peer> out;
  out.reserve(peers.size());
  for (const PeerInfo& p : peers) {
    out.push_back(surfeledit_proto_Peer{cstr(p.client_id), cstr(p.role), cstr(p.state), cstr(p.last_op),
                                        p.last_version, p.idle_ms, p.zero, p.one, p.deformable});
  }
  return out;
}

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

std::string message_of(const Error& e) {
  const std::string& f = e.field();
  std::string message = e.what();
  if (!f.empty() && message.compare(0, f.size() + 2, f + ": ") == 0) message.erase(0, f.size() + 2);
  return message;
}

void rethrow_prefixed(const Error& e, const std::string& prefix) {
  const std::string& f = e.field();
  if (f == prefix || f.rfind(prefix + ".", 0) == 0) throw e;
  throw Error(e.code(), f.empty() ? prefix : prefix + "." + f, message_of(e));
}

Status status_of(ErrorCode code) { return static_cast<Status>(static_cast<std::uint32_t>(code)); }

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

Setting to_reply(const NamedSetting& s) {
  Setting out;
  out.name = s.name;
  if (const double* number = std::get_if<double>(&s.value)) {
    out.kind = SettingKind::Number;
    out.number = *number;
  } else if (const std::int64_t* integer = std::get_if<std::int64_t>(&s.value)) {
    out.kind = SettingKind::Int;
    out.number = static_cast<double>(*integer);
  } else if (const bool* flag = std::get_if<bool>(&s.value)) {
    out.kind = SettingKind::Bool;
    out.flag = *flag;
  } else {
    out.kind = SettingKind::Text;
    out.text = std::get<std::string>(s.value);
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

CollisionStatsInfo to_reply(const CollisionStats& cs) {
  CollisionStatsInfo out;
  out.deformable = static_cast<std::uint64_t>(cs.deformable);
  out.tested = static_cast<std::uint64_t>(cs.tested);
  out.queries = static_cast<std::uint64_t>(cs.queries);
  out.colliding = static_cast<std::uint64_t>(cs.colliding);
  out.detect_ms = cs.detect_ms;
  out.preprocess_ms = cs.preprocess_ms;
  out.nv = static_cast<std::uint64_t>(cs.nv);
  out.np = static_cast<std::uint64_t>(cs.np);
  out.nu = static_cast<std::uint64_t>(cs.nu);
  return out;
}

StepResult to_reply(const surfeledit::StepResult& result, std::uint64_t seq) {
  StepResult step;
  step.seq = seq;
  step.moved = result.moved.size();
  step.center = {result.center.x(), result.center.y(), result.center.z()};
  step.detected = result.detected;
  if (result.depths.size() != result.colliding.size()) {
    throw std::logic_error("step outcome has " + std::to_string(result.depths.size()) + " depths for " +
                           std::to_string(result.colliding.size()) + " colliding ids");
  }
  step.colliding = result.colliding;
  step.depths = result.depths;
  step.stats = to_reply(result.stats);
  step.inserted = result.inserted;
  step.response = result.response;
  step.backoff_iterations = static_cast<std::uint32_t>(result.backoff.iterations);
  step.backoff_kept = result.backoff.kept;
  step.backoff_depth = result.backoff.final_depth;
  step.features = result.features;
  return step;
}

ReplyView::ReplyView(const Reply& reply) {
  msg_.client_id = cstr(reply.client_id);
  msg_.request_id = reply.request_id;
  msg_.status = static_cast<surfeledit_proto_Status>(reply.status);
  msg_.field = cstr(reply.field);
  msg_.message = cstr(reply.message);
  msg_.version = reply.version;

  timings_.reserve(reply.timings.size());
  for (const auto& [name, ms] : reply.timings) timings_.push_back(surfeledit_proto_Timing{cstr(name), ms});
  msg_.timings = borrow<dds_sequence_surfeledit_proto_Timing>(timings_);

  if (reply.state) {
    const StatePage& p = *reply.state;
    page_.full = p.full;
    page_.total = p.total;
    page_.offset = p.offset;
    page_.ids = borrow<dds_sequence_unsigned_long_long>(p.ids);
    page_.positions = borrow<dds_sequence_double>(p.positions);
    page_.normals = borrow<dds_sequence_double>(p.normals);
    page_.radii = borrow<dds_sequence_double>(p.radii);
    page_.removed = borrow<dds_sequence_unsigned_long_long>(p.removed);
    page_.clip_points = borrow<dds_sequence_double>(p.clip_points);
    page_.clip_dirs = borrow<dds_sequence_double>(p.clip_dirs);
  }
  msg_.state = borrow_one<dds_sequence_surfeledit_proto_StatePage>(&page_, reply.state.has_value());

  if (reply.session_info) {
    const SessionInfo& s = *reply.session_info;
    session_info_.name = cstr(s.name);
    session_info_.surfels = s.surfels;
    session_info_.has_regions = s.has_regions;
    session_info_.state_hash = s.state_hash;
    session_info_.clients = s.clients;
    session_info_.bytes_per_surfel = s.bytes_per_surfel;
    structures_.reserve(s.structures.size());
    for (const auto& [name, bytes] : s.structures) structures_.push_back(surfeledit_proto_Structure{cstr(name), bytes});
    session_info_.structures = borrow<dds_sequence_surfeledit_proto_Structure>(structures_);
    settings_.reserve(s.settings.size());
    for (const Setting& st : s.settings) {
      surfeledit_proto_Setting m{};
      m.name = cstr(st.name);
      m.kind = static_cast<std::int32_t>(st.kind);  // a SettingKind value (a long on the wire)
      m.number = st.number;
      m.flag = st.flag;
      m.text = cstr(st.text);
      settings_.push_back(m);
    }
    session_info_.settings = borrow<dds_sequence_surfeledit_proto_Setting>(settings_);
  }
  msg_.session_info =
      borrow_one<dds_sequence_surfeledit_proto_SessionInfo>(&session_info_, reply.session_info.has_value());

  if (reply.server_info) {
    const ServerInfo& s = *reply.server_info;
    server_info_.version = cstr(s.version);
    server_info_.uptime_s = s.uptime_s;
    session_names_.reserve(s.sessions.size());
    for (const auto& name : s.sessions) session_names_.push_back(cstr(name));
    server_info_.sessions = borrow<dds_sequence_string>(session_names_);
    server_info_.max_chunk_surfels = s.max_chunk_surfels;
    server_info_.max_model_surfels = s.max_model_surfels;
    server_info_.clients = s.clients;
    server_info_.upload_bytes = s.upload_bytes;
    server_info_.client_upload_bytes = s.client_upload_bytes;
    server_info_.max_upload_bytes = s.max_upload_bytes;
    server_info_.max_client_upload_bytes = s.max_client_upload_bytes;
    server_info_.reply_cache_bytes = s.reply_cache_bytes;
    server_info_.client_lease_s = s.client_lease_s;
    server_info_.session_grace_s = s.session_grace_s;
  }
  msg_.server_info =
      borrow_one<dds_sequence_surfeledit_proto_ServerInfo>(&server_info_, reply.server_info.has_value());

  if (reply.step) {
    step_.seq = reply.step->seq;
    step_.moved = reply.step->moved;
    step_.center = surfeledit_proto_Vec3{reply.step->center[0], reply.step->center[1], reply.step->center[2]};
    step_.detected = reply.step->detected;
    step_.colliding = borrow<dds_sequence_unsigned_long_long>(reply.step->colliding);
    step_.depths = borrow<dds_sequence_double>(reply.step->depths);
    const CollisionStatsInfo& cs = reply.step->stats;
    step_.stats = surfeledit_proto_CollisionStats{cs.deformable, cs.tested,        cs.queries, cs.colliding,
                                                  cs.detect_ms,  cs.preprocess_ms, cs.nv,      cs.np,
                                                  cs.nu};
    step_.inserted = borrow<dds_sequence_unsigned_long_long>(reply.step->inserted);
    step_.response = cstr(reply.step->response);
    step_.backoff_iterations = reply.step->backoff_iterations;
    step_.backoff_kept = reply.step->backoff_kept;
    step_.backoff_depth = reply.step->backoff_depth;
    step_.features = borrow<dds_sequence_unsigned_long_long>(reply.step->features);
  }
  msg_.step = borrow_one<dds_sequence_surfeledit_proto_StepResult>(&step_, reply.step.has_value());
  history_.reserve(reply.history.size());
  for (const HistoryInfo& h : reply.history) {
    history_.push_back(surfeledit_proto_HistoryEntry{h.version, cstr(h.op), cstr(h.client_id),
                                                     borrow<dds_sequence_unsigned_long_long>(h.touched), h.undone});
  }
  msg_.history = borrow<dds_sequence_surfeledit_proto_HistoryEntry>(history_);
  // Curves: OP_CURVES's first, then the merge's (each view refers to its CurveInfo).
  auto curve_views = [this](const std::vector<CurveInfo>& curves) {
    for (const CurveInfo& c : curves)
      curves_.push_back(surfeledit_proto_Curve{borrow<dds_sequence_double>(c.points), c.closed});
  };
  const std::size_t merge_curves = reply.merge ? reply.merge->curves.size() : 0;
  curves_.reserve(reply.curves.size() + merge_curves);
  curve_views(reply.curves);
  msg_.curves = borrow_range<dds_sequence_surfeledit_proto_Curve>(curves_.data(), reply.curves.size());
  if (reply.merge) {
    const MergeInfo& m = *reply.merge;
    curve_views(m.curves);
    merge_.removed = borrow<dds_sequence_unsigned_long_long>(m.removed);
    merge_.features = borrow<dds_sequence_unsigned_long_long>(m.features);
    merge_.moved = borrow<dds_sequence_unsigned_long_long>(m.moved);
    merge_.inserted = borrow<dds_sequence_unsigned_long_long>(m.inserted);
    merge_.curves = borrow_range<dds_sequence_surfeledit_proto_Curve>(curves_.data() + reply.curves.size(), merge_curves);
    merge_.merge_ms = m.merge_ms;
    merge_.crease_ms = m.crease_ms;
    merge_.curves_ms = m.curves_ms;
  }
  msg_.merge = borrow_one<dds_sequence_surfeledit_proto_MergeResult>(&merge_, reply.merge.has_value());
  msg_.token = cstr(reply.token);
  msg_.request_op = static_cast<std::int32_t>(reply.request_op);
  if (reply.blend) {
    const BlendInfo& b = *reply.blend;
    blend_.particles = b.particles;
    blend_.moved = borrow<dds_sequence_unsigned_long_long>(b.moved);
    blend_.inserted = borrow<dds_sequence_unsigned_long_long>(b.inserted);
    blend_.removed = borrow<dds_sequence_unsigned_long_long>(b.removed);
    blend_.energy = borrow<dds_sequence_double>(b.energy);
    blend_.substeps = b.substeps;
    blend_.ms = b.ms;
  }
  msg_.blend = borrow_one<dds_sequence_surfeledit_proto_BlendResult>(&blend_, reply.blend.has_value());
  if (reply.fill) {
    const FillInfo& f = *reply.fill;
    for (const HoleInfo& h : f.holes)
      holes_.push_back(surfeledit_proto_Hole{borrow<dds_sequence_unsigned_long_long>(h.boundary), h.diameter,
                                             borrow<dds_sequence_unsigned_long_long>(h.inserted)});
    fill_.holes = borrow<dds_sequence_surfeledit_proto_Hole>(holes_);
    fill_.skipped = f.skipped;
    fill_.inserted = borrow<dds_sequence_unsigned_long_long>(f.inserted);
    fill_.ms = f.ms;
  }
  msg_.fill = borrow_one<dds_sequence_surfeledit_proto_FillResult>(&fill_, reply.fill.has_value());
  peers_ = peer_views(reply.peers);
  msg_.peers = borrow<dds_sequence_surfeledit_proto_Peer>(peers_);
}

UpdateView::UpdateView(const UpdateChunk& c, bool compact) {
  if (!c.update) throw std::invalid_argument("update chunk without its update");
  const PreparedUpdate& u = *c.update;
  if (c.begin + c.count > u.surfels()) throw std::out_of_range("update chunk beyond its update");
  msg_.session = cstr(u.session);
  msg_.version = u.version;
  msg_.cause = cstr(u.cause);
  msg_.full = u.full;
  msg_.part = c.part;
  msg_.parts = c.parts;
  msg_.step = u.step;
  msg_.ids = borrow_range<dds_sequence_unsigned_long_long>(u.ids.data() + c.begin, c.count);
  if (compact) {
    compact_ = encode_compact(u, c.begin, c.count);
    msg_.origin = borrow_range<dds_sequence_double>(compact_.origin.data(), 3);
    msg_.positions_f32 = borrow<dds_sequence_octet>(compact_.positions);
    msg_.normals_oct16 = borrow<dds_sequence_octet>(compact_.normals);
    msg_.radii_f32 = borrow<dds_sequence_octet>(compact_.radii);
  } else {
    msg_.positions = borrow_range<dds_sequence_double>(u.positions.data() + 3 * c.begin, 3 * c.count);
    msg_.normals = borrow_range<dds_sequence_double>(u.normals.data() + 3 * c.begin, 3 * c.count);
    msg_.radii = borrow_range<dds_sequence_double>(u.radii.data() + c.begin, c.count);
  }
  const bool first = c.part == 0;
  msg_.removed = first ? borrow<dds_sequence_unsigned_long_long>(u.removed) : dds_sequence_unsigned_long_long{};
  msg_.detected = first && u.detected;
  msg_.colliding = first ? borrow<dds_sequence_unsigned_long_long>(u.colliding) : dds_sequence_unsigned_long_long{};
  if (!u.clip_points.empty()) {
    msg_.clip_points = borrow_range<dds_sequence_double>(u.clip_points.data() + 3 * c.begin, 3 * c.count);
    msg_.clip_dirs = borrow_range<dds_sequence_double>(u.clip_dirs.data() + 3 * c.begin, 3 * c.count);
  }
  msg_.author = cstr(u.author);
  msg_.presence = cstr(u.presence);
  if (first) peers_ = peer_views(u.peers);
  msg_.peers = borrow<dds_sequence_surfeledit_proto_Peer>(peers_);
}

}  // namespace surfeledit::service
