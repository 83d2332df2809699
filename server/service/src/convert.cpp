#include "surfeledit/service/convert.hpp"

#include <cmath>

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

char* cstr(const std::string& s) { return const_cast<char*>(s.c_str()); }

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
  }
  msg_.server_info =
      borrow_one<dds_sequence_surfeledit_proto_ServerInfo>(&server_info_, reply.server_info.has_value());

  if (reply.step) {
    step_.seq = reply.step->seq;
    step_.moved = reply.step->moved;
    step_.center = surfeledit_proto_Vec3{reply.step->center[0], reply.step->center[1], reply.step->center[2]};
  }
  msg_.step = borrow_one<dds_sequence_surfeledit_proto_StepInfo>(&step_, reply.step.has_value());
}

UpdateView::UpdateView(const UpdateChunk& c) {
  msg_.session = cstr(c.session);
  msg_.version = c.version;
  msg_.cause = cstr(c.cause);
  msg_.full = c.full;
  msg_.part = c.part;
  msg_.parts = c.parts;
  msg_.step = c.step;
  msg_.ids = borrow<dds_sequence_unsigned_long_long>(c.ids);
  msg_.positions = borrow<dds_sequence_double>(c.positions);
  msg_.normals = borrow<dds_sequence_double>(c.normals);
  msg_.radii = borrow<dds_sequence_double>(c.radii);
  msg_.removed = borrow<dds_sequence_unsigned_long_long>(c.removed);
}

}  // namespace surfeledit::service
