// Snapshot codecs of the session's images: see session_snapshot_images.hpp.
#include "session_snapshot_images.hpp"

#include "session_snapshot_values.hpp"

namespace surfeledit::snapshot_images {

using namespace snapshot_values;

RowsRefs rows_refs(const Tables& t, const RowsImage& r) { return {t.row_lists.at(r.rows.get()), t.row_lists.at(r.bent.get())}; }

ImageRefs image_refs(const Tables& t, const SessionImage& im) {
  ImageRefs refs;
  if (im.rows) refs.rows = rows_refs(t, *im.rows);
  refs.states = t.images.at(im.detector.get());
  refs.object = t.detectors.at(im.detector_object.get());
  if (im.tool_only) refs.tool_detector = t.detectors.at(im.tool_only->tool.detector.get());
  if (im.whole)
    for (const auto& [id, tool] : im.whole->tools) refs.tools.push_back(t.detectors.at(tool.detector.get()));
  return refs;
}

void put_tool_image(SnapshotWriter& out, std::uint32_t detector, const ToolImage& im) {
  out.boolean(im.fields.has_value());
  if (im.fields) put_fields(out, *im.fields);
  out.boolean(im.fields_kept);
  out.boolean(im.derive_detector);
  put_settings(out, im.settings);
  out.u32(detector);
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
void put_rows_image(SnapshotWriter& out, const RowsRefs& refs, const RowsImage& r) {
  out.u32(refs.rows);
  out.u32(refs.bent);
  out.mat(r.positions);
  out.mat(r.normals);
  out.mat(r.tangent_u);
  out.mat(r.tangent_v);
  put_pairs_of(out, r.version_runs);
}

void put_image(SnapshotWriter& out, const ImageRefs& refs, const SessionImage& im) {
  out.boolean(im.rows.has_value());
  if (im.rows) put_rows_image(out, refs.rows, *im.rows);
  out.boolean(im.tool_only.has_value());
  if (im.tool_only) {
    put_tool_image(out, refs.tool_detector, im.tool_only->tool);
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
    std::size_t k = 0;
    for (const auto& [id, tool] : w.tools) {
      out.str(id);
      put_tool_image(out, refs.tools.at(k++), tool);
    }
  }
  out.str(im.tool);
  out.u32(refs.states);
  out.u32(refs.object);
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

}  // namespace surfeledit::snapshot_images
