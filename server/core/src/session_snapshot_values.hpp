// Snapshot codecs of the session's plain values (session_snapshot.cpp writes the tables, images and
// history around them): pairs, the model, deformation fields, settings and the merge memo. Each get_*
// reads what its put_* wrote and checks it (a typed Error naming the field, never a crash).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/row_versions.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "surfeledit/core/surfel_model.hpp"
#include "surfeledit/core/tool.hpp"

namespace surfeledit::snapshot_values {

void put_pairs(SnapshotWriter& out, const std::vector<std::pair<std::uint64_t, std::uint64_t>>& v);
template <typename A, typename B>
std::vector<std::pair<A, B>> get_pairs(SnapshotReader& in, const char* what) {
  const std::size_t n = in.count(what, 16);
  std::vector<std::pair<A, B>> v;
  v.reserve(in.capacity(what, n, sizeof(std::pair<A, B>)));
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint64_t a = in.u64(what), b = in.u64(what);
    if (static_cast<std::uint64_t>(static_cast<B>(b)) != b) in.fail(what, "value out of range");
    v.emplace_back(static_cast<A>(a), static_cast<B>(b));
  }
  return v;
}

template <typename A, typename B>
void put_pairs_of(SnapshotWriter& out, const std::vector<std::pair<A, B>>& v) {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> w;
  w.reserve(v.capacity());
  for (const auto& [a, b] : v) w.emplace_back(a, b);
  put_pairs(out, w);
}

void put_model(SnapshotWriter& out, const SurfelModel& m);
SurfelModel get_model(SnapshotReader& in);
void put_fields(SnapshotWriter& out, const DeformationFields& f);
// `rows`: the model rows the fields must cover; kAnyRows: as many as they say (a tool-only image's
// fields cover the model as it was when the image was taken).
constexpr std::size_t kAnyRows = static_cast<std::size_t>(-1);
DeformationFields get_fields(SnapshotReader& in, std::size_t rows);
void put_settings(SnapshotWriter& out, const SessionSettings& s);
SessionSettings get_settings(SnapshotReader& in);
void put_merge(SnapshotWriter& out, const MergeMemo& m);
// Row versions: the floor, then the offsets. get_ fails ("row versions") with another row count or a floor
// above `version` (the session's).
void put_row_versions(SnapshotWriter& out, const RowVersions& v);
RowVersions get_row_versions(SnapshotReader& in, std::size_t rows, std::uint64_t version, const char* what);
MergeMemo get_merge(SnapshotReader& in, const CollisionDetector* detector);  // `detector`: the tool's, for origins_in_detector

}  // namespace surfeledit::snapshot_values
