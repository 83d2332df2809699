#include "surfeledit/service/sample_views.hpp"

#include <stdexcept>

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

}  // namespace

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
                                                  cs.nu,         cs.asleep};
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
