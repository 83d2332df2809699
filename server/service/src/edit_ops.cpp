// Handler functions of the edit ops: SET_REGIONS, DEFORM, CONFIGURE, REMOVE, UNDO, REDO, HISTORY, MERGE,
// CURVES.
// Every change carries the client id as its author in the session's history.
#include <algorithm>

#include "handler_ops.hpp"
#include "surfeledit/core/util.hpp"
#include "surfeledit/service/reply_values.hpp"

namespace surfeledit::service {

void serve_set_regions(OpContext& c) {
  const auto& args = args_of<SetRegionsArgs>(c);
  EditSession& s = *c.entry->session;
  const std::uint64_t before = s.version();
  prefixed("set_regions", [&] { s.set_regions(args.zero, args.one, c.command.client_id); });
  note_activity(*c.entry, c.command.client_id, Op::SetRegions, before, std::chrono::steady_clock::now());
  c.updates.push_back(make_update_event(c.command.session, s.version(), "regions"));
  // The client's tool changed: its peers see its new region sizes.
  c.updates.push_back(presence_event(c.state, *c.entry, c.command.session, c.command.client_id, "regions"));
}

void serve_deform(OpContext& c) {
  const auto& params = args_of<DeformParams>(c);
  SessionEntry& entry = *c.entry;
  const std::uint64_t version_before = entry.session->version();
  const auto t0 = std::chrono::steady_clock::now();
  surfeledit::StepResult result = prefixed("deform", [&] { return entry.session->deform(params, c.command.client_id); });
  c.reply.timings.emplace_back("apply", ms_since(t0));
  if (result.detected) c.reply.timings.emplace_back("detect", result.stats.detect_ms);
  if (!result.inserted.empty()) c.reply.timings.emplace_back("resample", result.resample_ms);
  entry.steps += 1;
  const std::uint64_t seq = result.seq > 0 ? result.seq : entry.steps;
  StepResult step = to_reply(result, seq);
  // A merge renumbers rows and removes surfels: its update is everything changed since the step began.
  UpdateEvent event = result.response == "merged"
                          ? changes_event(*entry.session, c.command.session, version_before)
                          : make_update_event(c.command.session, entry.session->version(), "deform");
  event.cause = "deform";
  event.step = seq;
  event.detected = result.detected;
  event.colliding = std::move(result.colliding);
  // Changed rows: moved or split ones plus the rows of inserted surfels (new ids are changes too).
  if (result.response == "merged") {
    event.colliding.clear();  // the merge removed them: the session's own state (none) is published
  } else {
    event.rows = std::move(result.moved);
  }
  if (!result.inserted.empty() && result.response != "merged") {
    append_rows(event.rows, entry.session->model(), result.inserted, "inserted");
    std::sort(event.rows.begin(), event.rows.end());
    event.rows.erase(std::unique(event.rows.begin(), event.rows.end()), event.rows.end());
  }
  c.reply.step = std::move(step);
  c.updates.push_back(std::move(event));
}

void serve_configure(OpContext& c) {
  // Errors keep the core's field: the setting's name (PROTOCOL.md).
  c.entry->session->configure(args_of<ConfigureArgs>(c).settings, c.command.client_id);
}

void serve_remove(OpContext& c) {
  EditSession& s = *c.entry->session;
  const std::uint64_t before = s.version();
  prefixed("remove", [&] { s.remove(args_of<RemoveArgs>(c).ids, c.command.client_id); });
  if (s.version() != before) {
    UpdateEvent event = changes_event(s, c.command.session, before);
    event.cause = "remove";
    c.updates.push_back(std::move(event));
  }
}

namespace {

// Undo or redo (`cause`) of the caller's own last change (issue 11 §3): what changed since is published
// like any change, with the collision state of the caller's tool.
void serve_swap(OpContext& c, std::uint64_t (EditSession::*swap)(const std::string&), const char* cause) {
  EditSession& s = *c.entry->session;
  const std::uint64_t before = s.version();
  (s.*swap)(c.command.client_id);
  UpdateEvent event = changes_event(s, c.command.session, before);
  event.cause = cause;
  event.detected = true;
  event.colliding = s.colliding(c.command.client_id);
  c.updates.push_back(std::move(event));
}

}  // namespace

void serve_undo(OpContext& c) {
  serve_swap(c, static_cast<std::uint64_t (EditSession::*)(const std::string&)>(&EditSession::undo), "undo");
}

void serve_redo(OpContext& c) {
  serve_swap(c, static_cast<std::uint64_t (EditSession::*)(const std::string&)>(&EditSession::redo), "redo");
}

namespace {

std::vector<CurveInfo> to_reply(const std::vector<Curve>& curves) {
  std::vector<CurveInfo> out;
  for (const Curve& k : curves)
    out.push_back({std::vector<double>(k.points.data(), k.points.data() + k.points.size()), k.closed});
  return out;
}

}  // namespace

void serve_merge(OpContext& c) {
  EditSession& s = *c.entry->session;
  const std::uint64_t before = s.version();
  const MergeOutcome m = prefixed("merge", [&] { return s.merge(args_of<MergeArgs>(c).crease, c.command.client_id); });
  c.reply.timings.emplace_back("merge", m.merge_ms);
  c.reply.timings.emplace_back("crease", m.crease_ms);
  c.reply.timings.emplace_back("curves", m.curves_ms);
  c.reply.merge = MergeInfo{m.removed, m.features, m.moved, m.inserted, to_reply(m.curves),
                            m.merge_ms, m.crease_ms, m.curves_ms};
  if (s.version() != before) {
    UpdateEvent event = changes_event(s, c.command.session, before);
    event.cause = "merge";
    event.detected = true;
    event.colliding = s.colliding(c.command.client_id);
    c.updates.push_back(std::move(event));
  }
}

void serve_curves(OpContext& c) {
  CurveParams p;
  p.refine_angle = args_of<CurvesArgs>(c).refine_angle;
  c.reply.curves = to_reply(prefixed("curves", [&] { return c.entry->session->intersection_curves(p, c.command.client_id); }));
}

void serve_history(OpContext& c) {
  for (const HistoryItem& h : c.entry->session->history())
    c.reply.history.push_back({h.version, h.op, h.author, h.touched, h.undone});
}

}  // namespace surfeledit::service
