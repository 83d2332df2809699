// EditSession::save / restore (edit_session.hpp, docs/journal.md "Snapshots"). Layout (format 3; see kFormat):
// magic, format version; the detector table (every detector object once, by identity: tools and
// history images refer to it by index, 0 = none); the detector-image table (each with the index of
// a detector that reads it); the table of shared row lists; then the session's scalars, model, row
// versions, removal log, rest radii, tools, acting tool, history entries and spare buffers.
#include <map>
#include <unordered_map>

#include "session_snapshot_values.hpp"
#include "surfeledit/core/detector_snapshot.hpp"
#include "surfeledit/core/edit_session.hpp"

namespace surfeledit {

using namespace snapshot_values;

namespace {

constexpr std::uint32_t kMagic = 0x53534553;  // "SESS"
constexpr std::uint32_t kFormat = 3;  // 2: rows images name their `bent` rows; a stale tool keeps its held rigid rows;
                                      // 3: merge origins may be the tool detector's (MergeMemo::origins_in_detector),
                                      // row versions as a floor and 32-bit offsets (RowVersions)

// Pointer tables: index 0 is null, objects from 1 in first-seen order.
template <typename T>
struct Table {
  std::unordered_map<const T*, std::uint32_t> index;
  std::vector<const T*> list;
  void add(const T* p) {
    if (p && index.emplace(p, static_cast<std::uint32_t>(list.size() + 1)).second) list.push_back(p);
  }
  std::uint32_t at(const T* p) const { return p ? index.at(p) : 0; }
  // Like at(), but 0 for a pointer not in the table (never dereferenced: it may be stale).
  std::uint32_t find(const T* p) const {
    const auto it = index.find(p);
    return it == index.end() ? 0 : it->second;
  }
};

struct Tables {
  Table<CollisionDetector> detectors;
  Table<DetectorImage> images;
  std::vector<const CollisionDetector*> image_owner;  // per image: the detector that reads it
  Table<IndexList> row_lists;
  std::string why;  // not snapshottable: why

  void detector(const CollisionDetector* d, const char* where) {
    if (d && !d->snapshottable() && why.empty())
      why = std::string(where) + ": collision detector '" + to_string(d->params().algorithm) +
            "' with a hierarchy, clusters, Improved's sweep or an inside model has no snapshot";
    detectors.add(d);
  }
  void rows_image(const RowsImage& r) {
    row_lists.add(r.rows.get());
    row_lists.add(r.bent.get());
  }
  void image(const SessionImage& im) {
    detector(im.detector_object.get(), "history");
    if (im.detector) {
      if (!im.detector_object && why.empty()) why = "history: a detector image without its detector";
      const std::size_t before = images.list.size();
      images.add(im.detector.get());
      if (images.list.size() > before) image_owner.push_back(im.detector_object.get());
    }
    if (!im.complete && why.empty()) why = "history: an incomplete image";
    if (im.rows) rows_image(*im.rows);
    if (im.tool_only) detector(im.tool_only->tool.detector.get(), "history");
    if (im.whole)
      for (const auto& [id, t] : im.whole->tools) detector(t.detector.get(), "history");
  }
};

// The objects the tables index, on load.
struct Loaded {
  std::vector<std::shared_ptr<CollisionDetector>> detectors;  // [0] null
  std::vector<std::shared_ptr<const DetectorImage>> images;   // [0] null
  std::vector<std::shared_ptr<const IndexList>> row_lists;    // [0] null

  template <typename T>
  static const T& pick(SnapshotReader& in, const std::vector<T>& v, const char* what) {
    const std::uint32_t k = in.u32(what);
    if (k >= v.size()) in.fail(what, "index " + std::to_string(k) + " out of range");
    return v[k];
  }
};

void put_tool_image(SnapshotWriter& out, const Tables& t, const ToolImage& im) {
  out.boolean(im.fields.has_value());
  if (im.fields) put_fields(out, *im.fields);
  out.boolean(im.fields_kept);
  out.boolean(im.derive_detector);
  put_settings(out, im.settings);
  out.u32(t.detectors.at(im.detector.get()));
  put_merge(out, im.merge);
  out.vec(im.colliding);
  out.u64(im.steps);
  out.boolean(im.stale);
}

ToolImage get_tool_image(SnapshotReader& in, const Loaded& l, std::size_t rows) {
  ToolImage im;
  if (in.boolean("tool fields")) im.fields = get_fields(in, rows);
  im.fields_kept = in.boolean("tool fields kept");
  im.derive_detector = in.boolean("tool derives its detector");
  if (im.fields_kept && im.fields) in.fail("tool fields kept", "an image that keeps the fields holds none");
  im.settings = get_settings(in);
  im.detector = Loaded::pick(in, l.detectors, "tool detector");
  im.merge = get_merge(in, im.detector.get());
  im.colliding = in.vec<SurfelId>("tool colliding");
  im.steps = in.u64("tool steps");
  im.stale = in.boolean("tool stale");
  return im;
}

// A rows image (an entry's or a spare buffer); get_rows_image reads it.
void put_rows_image(SnapshotWriter& out, const Tables& t, const RowsImage& r) {
  out.u32(t.row_lists.at(r.rows.get()));
  out.u32(t.row_lists.at(r.bent.get()));
  out.mat(r.positions);
  out.mat(r.normals);
  out.mat(r.tangent_u);
  out.mat(r.tangent_v);
  put_pairs_of(out, r.version_runs);
}

void put_image(SnapshotWriter& out, const Tables& t, const SessionImage& im) {
  out.boolean(im.rows.has_value());
  if (im.rows) put_rows_image(out, t, *im.rows);
  out.boolean(im.tool_only.has_value());
  if (im.tool_only) {
    put_tool_image(out, t, im.tool_only->tool);
    out.f64(im.tool_only->history.history_mb);
  }
  out.boolean(im.whole.has_value());
  if (im.whole) {
    const WholeImage& w = *im.whole;
    put_model(out, w.model);
    out.u64(w.model_version);
    put_row_versions(out, w.row_version);
    out.mat(w.rest_radius);
    out.f64(w.history.history_mb);
    out.u64(w.tools.size());
    for (const auto& [id, tool] : w.tools) {
      out.str(id);
      put_tool_image(out, t, tool);
    }
  }
  out.str(im.tool);
  out.u32(t.images.at(im.detector.get()));
  out.u32(t.detectors.at(im.detector_object.get()));
  out.boolean(im.stale);
  out.vec(im.colliding);
  out.u64(im.steps);
  out.boolean(im.complete);
}

RowsImage get_rows_image(SnapshotReader& in, const Loaded& l) {
  RowsImage r;
  r.rows = Loaded::pick(in, l.row_lists, "image rows");
  r.bent = Loaded::pick(in, l.row_lists, "image bent rows");
  r.positions = in.mat<Points>("image positions");
  r.normals = in.mat<Points>("image normals");
  r.tangent_u = in.mat<Points>("image tangent_u");
  r.tangent_v = in.mat<Points>("image tangent_v");
  r.version_runs = get_pairs<std::uint64_t, std::uint32_t>(in, "image version runs");
  const std::size_t n = r.rows ? r.rows->size() : 0;
  const std::size_t nb = r.bent ? r.bent->size() : n;  // rows with normals and tangents
  std::size_t runs = 0;
  for (const auto& run : r.version_runs) runs += run.second;
  if (static_cast<std::size_t>(r.positions.rows()) != n || static_cast<std::size_t>(r.normals.rows()) != nb ||
      (r.tangent_u.rows() != 0 && static_cast<std::size_t>(r.tangent_u.rows()) != nb) ||
      r.tangent_v.rows() != r.tangent_u.rows() || runs != n) {
    in.fail("rows image", "arrays do not match its rows");
  }
  return r;
}

SessionImage get_image(SnapshotReader& in, const Loaded& l) {
  SessionImage im;
  if (in.boolean("image has rows")) im.rows = get_rows_image(in, l);
  if (in.boolean("image has tool")) {
    ToolOnlyImage t;
    t.tool = get_tool_image(in, l, kAnyRows);
    t.history.history_mb = in.f64("image history_mb");
    im.tool_only = std::move(t);
  }
  if (in.boolean("image has whole")) {
    WholeImage w;
    w.model = get_model(in);
    w.model_version = in.u64("image model version");
    const std::size_t rows = static_cast<std::size_t>(w.model.size());
    w.row_version = get_row_versions(in, rows, ~std::uint64_t{0}, "image row versions");
    w.rest_radius = in.mat<Values>("image rest radii");
    w.history.history_mb = in.f64("image history_mb");
    if (w.rest_radius.size() != 0 && static_cast<std::size_t>(w.rest_radius.size()) != rows)
      in.fail("whole image", "per-row arrays do not match the model");
    const std::size_t n = in.count("image tools", 8);
    for (std::size_t k = 0; k < n; ++k) {
      std::string id = in.str("image tool author");
      w.tools.emplace(std::move(id), get_tool_image(in, l, rows));
    }
    im.whole = std::move(w);
  }
  if (int(im.rows.has_value()) + int(im.tool_only.has_value()) + int(im.whole.has_value()) != 1)
    in.fail("image", "not exactly one of rows, tool and whole");
  im.tool = in.str("image tool");
  im.detector = Loaded::pick(in, l.images, "image detector states");
  im.detector_object = Loaded::pick(in, l.detectors, "image detector");
  im.stale = in.boolean("image stale");
  im.colliding = in.vec<SurfelId>("image colliding");
  im.steps = in.u64("image steps");
  im.complete = in.boolean("image complete");
  return im;
}

void put_item(SnapshotWriter& out, const HistoryItem& item) {
  out.u64(item.version);
  out.str(item.op);
  out.str(item.author);
  out.vec(item.touched);
  out.boolean(item.undone);
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
  for (const HistoryEntry& e : history_.entries()) t.image(e.image);
  return t.why;
}

void EditSession::save(SnapshotWriter& out) const {
  Tables t;
  for (const auto& [id, tool] : tools_) {
    t.detector(tool.detector.get(), "tool");
    t.row_lists.add(tool.shared_rows.get());
  }
  for (const HistoryEntry& e : history_.entries()) t.image(e.image);
  for (const RowsImage& r : history_.spare()) t.rows_image(r);
  if (!t.why.empty()) throw Error(ErrorCode::Internal, "snapshot", "session '" + name_ + "' is not snapshottable: " + t.why);

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
    put_item(out, e.item);
    put_image(out, t, e.image);
    out.u64(e.bytes);
    out.u64(e.stamp);
    out.u64(e.applied_at);
  }
  out.u64(history_.spare().size());
  for (const RowsImage& r : history_.spare()) put_rows_image(out, t, r);
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
    e.image = get_image(in, l);
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
