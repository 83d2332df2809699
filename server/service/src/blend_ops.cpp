// Handler functions of the blend tool's ops (issue 10): BLEND, BOOLEAN (model B from the client's completed
// upload, upload.hpp), FILL_HOLES. Each is one history entry of the session, authored by the client, and one
// update (everything changed since the op began).
#include "handler_ops.hpp"

namespace surfeledit::service {

namespace {

// The update of an op that changed the session since `before`.
void publish_changes(OpContext& c, std::uint64_t before, const char* cause) {
  EditSession& s = *c.entry->session;
  if (s.version() == before) return;
  UpdateEvent event = changes_event(s, c.command.session, before);
  event.cause = cause;
  c.updates.push_back(std::move(event));
}

}  // namespace

void serve_blend(OpContext& c) {
  const auto& args = args_of<BlendArgs>(c);
  EditSession& s = *c.entry->session;
  const std::uint64_t before = s.version();
  const BlendOutcome b = prefixed("blend", [&] {
    BlendParams p = args.params;
    p.repulsion = parse_enum<RepulsionKind>(args.repulsion, "repulsion");
    p.weight = parse_enum<WeightKind>(args.weight, "weight");
    p.neighbours = parse_enum<NeighbourMode>(args.neighbourhood, "neighbourhood");
    p.projection = parse_enum<ProjectionKind>(args.projection, "projection");
    return s.blend(p, args.features, c.command.client_id);
  });
  c.reply.timings.emplace_back("blend", b.ms);
  c.reply.blend = BlendInfo{static_cast<std::uint32_t>(b.particles), b.moved, b.inserted, b.removed, b.energy,
                            static_cast<std::uint32_t>(b.substeps), b.ms};
  publish_changes(c, before, "blend");
}

void serve_boolean(OpContext& c) {
  const auto& args = args_of<BooleanArgs>(c);
  EditSession& s = *c.entry->session;
  Upload* upload = c.state.uploads.find(c.command.client_id, c.command.session);
  if (!upload) throw Error(ErrorCode::Conflict, "boolean_op", "no upload of model B: send OP_LOAD_BEGIN and its chunks first");
  if (!upload->complete()) {
    throw Error(ErrorCode::Conflict, "load_begin.total",
                "upload of model B incomplete: received " + std::to_string(upload->received()) + " of " +
                    std::to_string(upload->total()) + " surfels");
  }
  const BooleanOp op = prefixed("boolean_op", [&] { return parse_enum<BooleanOp>(args.op, "op"); });
  const std::uint64_t before = s.version();
  // The upload is consumed only when the op succeeded (a refused op leaves it for a retry).
  const MergeOutcome m = prefixed("boolean_op", [&] { return s.boolean(op, upload->arrays(), {}, c.command.client_id); });
  c.state.uploads.erase(c.command.client_id, c.command.session);
  c.reply.timings.emplace_back("boolean", m.total_ms);
  c.reply.merge = MergeInfo{m.removed, m.features, m.moved, m.inserted, {}, m.merge_ms, m.crease_ms, m.curves_ms};
  publish_changes(c, before, "boolean");
}

void serve_fill_holes(OpContext& c) {
  const auto& args = args_of<FillHolesArgs>(c);
  EditSession& s = *c.entry->session;
  const std::uint64_t before = s.version();
  const FillOutcome f = prefixed("fill_holes", [&] {
    HoleParams p = args.params;
    p.projection = parse_enum<ProjectionKind>(args.projection, "projection");
    return s.fill_holes(p, args.boundary, c.command.client_id);
  });
  c.reply.timings.emplace_back("fill_holes", f.ms);
  FillInfo info;
  for (const HoleOutcome& h : f.holes) info.holes.push_back({h.boundary, h.diameter, h.inserted});
  info.skipped = static_cast<std::uint32_t>(f.skipped);
  info.inserted = f.inserted;
  info.ms = f.ms;
  c.reply.fill = std::move(info);
  publish_changes(c, before, "fill_holes");
}

}  // namespace surfeledit::service
