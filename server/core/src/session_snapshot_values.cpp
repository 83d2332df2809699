// Snapshot codecs of the session's plain values (session_snapshot_values.hpp).
#include "session_snapshot_values.hpp"

#include <string>

namespace surfeledit::snapshot_values {

void put_pairs(SnapshotWriter& out, const std::vector<std::pair<std::uint64_t, std::uint64_t>>& v) {
  out.u64(v.size());
  out.u64(v.capacity());
  for (const auto& [a, b] : v) {
    out.u64(a);
    out.u64(b);
  }
}
// A flag (false: no model, as before the first load), then the arrays, ids and next id.
void put_model(SnapshotWriter& out, const SurfelModel& m) {
  out.boolean(!m.empty());
  if (m.empty()) return;
  const SurfelArrays& a = m.arrays();
  out.mat(a.positions);
  out.mat(a.normals);
  out.mat(a.radii);
  out.mat(a.tangent_u);
  out.mat(a.tangent_v);
  out.mat(a.colors);
  out.mat(a.clip_points);
  out.mat(a.clip_dirs);
  out.vec(m.ids());
  out.u64(m.next_id());
}

SurfelModel get_model(SnapshotReader& in) {
  if (!in.boolean("has model")) return SurfelModel();
  SurfelArrays a;
  a.positions = in.mat<Points>("positions");
  a.normals = in.mat<Points>("normals");
  a.radii = in.mat<Values>("radii");
  a.tangent_u = in.mat<Points>("tangent_u");
  a.tangent_v = in.mat<Points>("tangent_v");
  a.colors = in.mat<Colors>("colors");
  a.clip_points = in.mat<Points>("clip_points");
  a.clip_dirs = in.mat<Points>("clip_dirs");
  IdList ids = in.vec<SurfelId>("ids");
  const SurfelId next = in.u64("next id");
  if (ids.empty()) in.fail("ids", "an empty model");
  return SurfelModel::from_parts(std::move(a), std::move(ids), next);
}

void put_fields(SnapshotWriter& out, const DeformationFields& f) {
  out.vec(f.regions);
  out.vec(f.deformable);
  out.mat(f.blend);
  out.f64(f.box_centre.x());
  out.f64(f.box_centre.y());
  out.f64(f.box_centre.z());
  out.f64(f.box_extent);
}

DeformationFields get_fields(SnapshotReader& in, std::size_t rows) {
  DeformationFields f;
  f.regions = in.vec<Region>("regions");
  if (rows == kAnyRows) rows = f.regions.size();
  f.deformable = in.vec<Index>("fields deformable rows");
  f.blend = in.mat<BlendRows>("fields blend");
  const double x = in.f64("box centre"), y = in.f64("box centre"), z = in.f64("box centre");
  f.box_centre = Vec3(x, y, z);
  f.box_extent = in.f64("box extent");
  if (f.regions.size() != rows) in.fail("regions", "not one per row");
  Index last = -1;
  std::size_t deformable = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    if (static_cast<std::uint8_t>(f.regions[r]) > static_cast<std::uint8_t>(Region::One)) in.fail("regions", "unknown region");
    deformable += f.regions[r] != Region::Zero;
  }
  for (Index r : f.deformable) {
    if (r <= last || static_cast<std::size_t>(r) >= rows || f.regions[r] == Region::Zero)
      in.fail("fields deformable rows", "not the ascending deformable rows");
    last = r;
  }
  const bool stored = f.blend.rows() != 0;  // none: every deformable row is F1 (DeformationFields::blend)
  if (f.deformable.size() != deformable || (stored && static_cast<std::size_t>(f.blend.rows()) != deformable))
    in.fail("fields", "not one blend row per deformable row");
  if (!stored)
    for (Index r : f.deformable)
      if (f.regions[static_cast<std::size_t>(r)] != Region::One) in.fail("fields", "no blend rows but a row not in F1");
  return f;
}

void put_settings(SnapshotWriter& out, const SessionSettings& s) {
  const std::vector<NamedSetting> all = describe(s);
  out.u64(all.size());
  for (const NamedSetting& n : all) {
    out.str(n.name);
    out.u8(static_cast<std::uint8_t>(n.value.index()));
    if (const double* d = std::get_if<double>(&n.value)) out.f64(*d);
    else if (const std::int64_t* i = std::get_if<std::int64_t>(&n.value)) out.i64(*i);
    else if (const bool* b = std::get_if<bool>(&n.value)) out.boolean(*b);
    else out.str(std::get<std::string>(n.value));
  }
}

SessionSettings get_settings(SnapshotReader& in) {
  const std::size_t n = in.count("settings", 10);
  std::vector<NamedSetting> all;
  for (std::size_t k = 0; k < n; ++k) {
    NamedSetting s;
    s.name = in.str("setting name");
    switch (in.u8("setting kind")) {
      case 0: s.value = in.f64("setting"); break;
      case 1: s.value = in.i64("setting"); break;
      case 2: s.value = in.boolean("setting"); break;
      case 3: s.value = in.str("setting"); break;
      default: in.fail("setting kind", "unknown");
    }
    all.push_back(std::move(s));
  }
  try {
    return apply_settings(SessionSettings{}, all);
  } catch (const Error& e) {
    in.fail("settings", e.what());
  }
}

void put_row_versions(SnapshotWriter& out, const RowVersions& v) {
  out.u64(v.floor());
  out.vec(v.offsets());
}

RowVersions get_row_versions(SnapshotReader& in, std::size_t rows, std::uint64_t version, const char* what) {
  const std::uint64_t floor = in.u64(what);
  std::vector<std::uint32_t> offsets = in.vec<std::uint32_t>(what);
  if (offsets.size() != rows) in.fail(what, "one per model row");
  if (floor > version) in.fail(what, "a floor above the session's version");
  return RowVersions::from_parts(floor, std::move(offsets));
}

void put_merge(SnapshotWriter& out, const MergeMemo& m) {
  out.boolean(m.origins_in_detector);
  out.mat(m.origin_positions);
  out.mat(m.origin_normals);
  out.mat(m.crease_positions);
  out.mat(m.crease_radii);
  out.vec(m.features);
  out.vec(m.crease_moved);
  out.mat(m.crease_from);
  out.vec(m.crease_copies);
  out.boolean(m.open_region);
}

MergeMemo get_merge(SnapshotReader& in, const CollisionDetector* detector) {
  MergeMemo m;
  m.origins_in_detector = in.boolean("merge origins in detector");
  m.origin_positions = in.mat<Points>("merge origins");
  m.origin_normals = in.mat<Points>("merge origin normals");
  m.crease_positions = in.mat<Points>("crease positions");
  m.crease_radii = in.mat<Values>("crease radii");
  m.features = in.vec<SurfelId>("features");
  m.crease_moved = in.vec<SurfelId>("crease moved");
  m.crease_from = in.mat<Points>("crease from");
  m.crease_copies = in.vec<SurfelId>("crease copies");
  m.open_region = in.boolean("open region");
  if (static_cast<std::size_t>(m.crease_from.rows()) != m.crease_moved.size()) in.fail("crease from", "one row per moved id");
  if (m.origin_positions.rows() != m.origin_normals.rows()) in.fail("merge origins", "positions and normals differ in length");
  if (m.origins_in_detector) {
    if (m.origin_positions.rows() != 0) in.fail("merge origins", "held twice (in the detector and copied)");
    if (!detector || !detector->reset_rows().positions) in.fail("merge origins", "in a detector that keeps none");
  }
  return m;
}

}  // namespace surfeledit::snapshot_values
