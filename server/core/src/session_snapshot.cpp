// EditSession::snapshot_view / save / restore (edit_session.hpp, docs/journal.md "Snapshots"). Layout (format 3; see kFormat):
// magic, format version; the detector table (every detector object once, by identity: tools and
// history images refer to it by index, 0 = none); the detector-image table (each with the index of
// a detector that reads it); the table of shared row lists; then the session's scalars, model, row
// versions, removal log, rest radii, tools, acting tool, history entries and spare buffers.
#include <map>

#include "session_snapshot_images.hpp"
#include "session_snapshot_values.hpp"
#include "session_snapshot_view.hpp"
#include "surfeledit/core/detector_snapshot.hpp"
#include "surfeledit/core/edit_session.hpp"

namespace surfeledit {

using namespace snapshot_images;
using namespace snapshot_values;

namespace {

constexpr std::uint32_t kMagic = 0x53534553;  // "SESS"
constexpr std::uint32_t kFormat = 4;  // 2: rows images name their `bent` rows; a stale tool keeps its held rigid rows;
                                      // 3: merge origins may be the tool detector's (MergeMemo::origins_in_detector),
                                      // row versions as a floor and 32-bit offsets (RowVersions);
                                      // 4: a row detector's Robust states without an old position

// An entry's item: version, op, author, then its touched ids (the view shares them) and its undone flag.
void put_item_head(SnapshotWriter& out, const HistoryItem& item) {
  out.u64(item.version);
  out.str(item.op);
  out.str(item.author);
}

HistoryItem get_item(SnapshotReader& in) {
  HistoryItem item;
  item.version = in.u64("entry version");
  item.op = in.str("entry op");
  item.author = in.str("entry author");
  item.touched = in.vec<SurfelId>("entry touched");
  item.undone = in.boolean("entry undone");
  return item;
}

}  // namespace

std::string EditSession::not_snapshottable() const {
  Tables t;
  for (const auto& [id, tool] : tools_) t.detector(tool.detector.get(), "tool");
  for (const HistoryEntry& e : history_.entries()) t.image(*e.image);
  return t.why;
}

void EditSession::save(SnapshotWriter& out) const { snapshot_view().encode(out); }

SessionSnapshotView EditSession::snapshot_view() const {
  Tables t;
  for (const auto& [id, tool] : tools_) {
    t.detector(tool.detector.get(), "tool");
    t.row_lists.add(tool.shared_rows.get());
  }
  for (const HistoryEntry& e : history_.entries()) t.image(*e.image);
  for (const RowsImage& r : history_.spare()) t.rows_image(r);
  if (!t.why.empty()) throw Error(ErrorCode::Internal, "snapshot", "session '" + name_ + "' is not snapshottable: " + t.why);

  // Everything is encoded here but the history's images, which the view shares (with their pointers as
  // table indices): each entry's image follows the bytes before it.
  SessionSnapshotView view;
  SnapshotWriter out;
  out.u32(kMagic);
  out.u32(kFormat);
  out.u64(t.detectors.list.size());
  for (const CollisionDetector* d : t.detectors.list) save_detector(out, *d);
  out.u64(t.images.list.size());
  for (std::size_t k = 0; k < t.images.list.size(); ++k) {
    out.u32(t.detectors.at(t.image_owner[k]));
    t.image_owner[k]->save_image_state(out, *t.images.list[k]);
  }
  out.u64(t.row_lists.list.size());
  for (const IndexList* rows : t.row_lists.list) out.vec(*rows);

  out.u64(version_);
  out.u64(model_version_);
  put_model(out, model_);
  put_row_versions(out, row_version_);
  put_pairs_of(out, removed_log_);
  out.mat(rest_radius_);
  out.f64(history_params_.history_mb);
  out.u64(tools_.size());
  for (const auto& [id, tool] : tools_) {
    out.str(id);
    out.boolean(tool.fields != nullptr);
    if (tool.fields) put_fields(out, *tool.fields);
    put_settings(out, tool.settings);
    out.u32(t.detectors.at(tool.detector.get()));
    out.vec(tool.colliding);
    out.u64(tool.steps);
    put_merge(out, tool.merge);
    out.boolean(tool.stale);
    out.boolean(tool.stale_rows_known);
    out.vec(tool.stale_rows);
    // Held rows are read only while the tool is stale with known rows (Tool::held_before); otherwise none.
    const bool held = tool.stale && tool.stale_rows_known;
    out.vec(held ? tool.held_rows : IndexList());
    out.mat(held ? tool.held.positions : Points(0, 3));
    out.mat(held ? tool.held.normals : Points(0, 3));
    out.mat(held ? tool.held.radii : Values());
    out.u32(t.row_lists.at(tool.shared_rows.get()));
    out.u64(tool.fresh_at);
    out.u32(t.detectors.find(tool.fresh_object));
  }
  out.boolean(tool_ != nullptr);
  out.str(tool_id_);
  const auto& entries = history_.entries();
  out.u64(entries.size());
  for (const HistoryEntry& e : entries) {
    put_item_head(out, e.item);
    view.pieces_.push_back({out.take(), e.touched, nullptr, {}});
    out = SnapshotWriter();
    out.boolean(e.item.undone);
    view.pieces_.push_back({out.take(), nullptr, e.image, image_refs(t, *e.image)});
    out = SnapshotWriter();
    out.u64(e.bytes);
    out.u64(e.stamp);
    out.u64(e.applied_at);
  }
  out.u64(history_.spare().size());
  for (const RowsImage& r : history_.spare()) put_rows_image(out, rows_refs(t, r), r);
  view.pieces_.push_back({out.take(), nullptr, nullptr, {}});
  return view;
}

void EditSession::restore(SnapshotReader& in) {
  if (in.u32("magic") != kMagic) in.fail("magic", "not a session snapshot");
  const std::uint32_t format = in.u32("format");
  if (format != kFormat) in.fail("format", "unknown snapshot format version " + std::to_string(format) +
                                               " (this server reads version " + std::to_string(kFormat) + ")");
  Loaded l;
  l.detectors.emplace_back();
  l.images.emplace_back();
  l.row_lists.emplace_back();
  const std::size_t detectors = in.count("detectors", 16);
  for (std::size_t k = 0; k < detectors; ++k) l.detectors.push_back(load_detector(in));
  const std::size_t images = in.count("detector images", 8);
  for (std::size_t k = 0; k < images; ++k) {
    const std::shared_ptr<CollisionDetector>& owner = Loaded::pick(in, l.detectors, "image owner");
    if (!owner) in.fail("image owner", "none");
    l.images.push_back(owner->load_image_state(in));
  }
  const std::size_t lists = in.count("row lists", 16);
  for (std::size_t k = 0; k < lists; ++k) {
    auto rows = std::make_shared<IndexList>(in.vec<Index>("row list"));
    Index last = -1;
    for (Index r : *rows) {
      if (r <= last) in.fail("row list", "not ascending");
      last = r;
    }
    l.row_lists.push_back(std::move(rows));
  }

  const std::uint64_t version = in.u64("version");
  const std::uint64_t model_version = in.u64("model version");
  SurfelModel model = get_model(in);
  const std::size_t rows = static_cast<std::size_t>(model.size());
  RowVersions row_version = get_row_versions(in, rows, version, "row versions");
  auto removed_log = get_pairs<std::uint64_t, SurfelId>(in, "removal log");
  Values rest_radius = in.mat<Values>("rest radii");
  HistoryParams history_params;
  history_params.history_mb = in.f64("history_mb");
  if (rest_radius.size() != 0 && static_cast<std::size_t>(rest_radius.size()) != rows)
    in.fail("rest radii", "per-row arrays do not match the model");
  std::map<std::string, Tool> tools;
  const std::size_t n_tools = in.count("tools", 8);
  for (std::size_t k = 0; k < n_tools; ++k) {
    std::string id = in.str("tool author");
    Tool& tool = tools[id];
    if (in.boolean("tool fields")) tool.fields = std::make_unique<DeformationFields>(get_fields(in, rows));
    tool.settings = get_settings(in);
    tool.detector = Loaded::pick(in, l.detectors, "tool detector");
    tool.colliding = in.vec<SurfelId>("tool colliding");
    tool.steps = in.u64("tool steps");
    tool.merge = get_merge(in, tool.detector.get());
    tool.stale = in.boolean("tool stale");
    tool.stale_rows_known = in.boolean("tool stale rows known");
    tool.stale_rows = in.vec<Index>("tool stale rows");
    tool.held_rows = in.vec<Index>("tool held rows");
    tool.held.positions = in.mat<Points>("tool held positions");
    tool.held.normals = in.mat<Points>("tool held normals");
    tool.held.radii = in.mat<Values>("tool held radii");
    const auto held = static_cast<Eigen::Index>(tool.held_rows.size());
    if (tool.held.positions.rows() != held || tool.held.normals.rows() != held || tool.held.radii.size() != held)
      in.fail("tool held rows", "arrays of different lengths");
    for (std::size_t j = 0; j < tool.held_rows.size(); ++j)
      if (tool.held_rows[j] < 0 || static_cast<std::size_t>(tool.held_rows[j]) >= rows || (j > 0 && tool.held_rows[j] <= tool.held_rows[j - 1]))
        in.fail("tool held rows", "not ascending model rows");
    tool.shared_rows = Loaded::pick(in, l.row_lists, "tool row list");
    tool.fresh_at = in.u64("tool fresh at");
    tool.fresh_object = Loaded::pick(in, l.detectors, "tool fresh detector").get();
  }
  const bool has_acting = in.boolean("acting tool");
  std::string acting = in.str("acting tool author");
  if (has_acting && !tools.count(acting)) in.fail("acting tool", "no such tool");
  std::deque<HistoryEntry> entries;
  const std::size_t n_entries = in.count("history entries", 16);
  for (std::size_t k = 0; k < n_entries; ++k) {
    HistoryEntry e;
    e.item = get_item(in);
    e.image = std::make_shared<SessionImage>(get_image(in, l));
    e.bytes = in.u64("entry bytes");
    e.stamp = in.u64("entry stamp");
    e.applied_at = in.u64("entry applied_at");
    entries.push_back(std::move(e));
  }
  std::vector<RowsImage> spare;
  const std::size_t n_spare = in.count("spare buffers", 8);
  if (n_spare > 2) in.fail("spare buffers", "more than two");
  for (std::size_t k = 0; k < n_spare; ++k) spare.push_back(get_rows_image(in, l));
  in.expect_end();

  // Everything read and checked: replace the state.
  version_ = version;
  model_version_ = model_version;
  model_ = std::move(model);
  row_version_ = std::move(row_version);
  removed_log_ = std::move(removed_log);
  rest_radius_ = std::move(rest_radius);
  history_params_ = history_params;
  tools_ = std::move(tools);
  tool_ = has_acting ? &tools_.at(acting) : nullptr;
  tool_id_ = has_acting ? acting : std::string();
  history_.restore(std::move(entries), std::move(spare));
}

}  // namespace surfeledit
