// A surfel model: dense per-surfel arrays plus stable ids.
//
// Rows are kept in ascending id order: inserted surfels get fresh, larger ids and are
// appended; removal compacts the arrays and keeps the order. An id is never reused.
#pragma once

#include <optional>

#include "surfeledit/core/rank_bits.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

using Colors = Eigen::Matrix<std::uint8_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Plain per-surfel arrays, as loaded or sent by a client. Optional arrays are empty (0 rows).
struct SurfelArrays {
  Points positions;  // #P by 3, model units
  Points normals;    // #P by 3, outward; normalised on load (zero normals are rejected)
  Values radii;      // #P disc radii (> 0); empty -> estimated from neighbour spacing
  Points tangent_u;  // #P by 3 or empty: first tangent axis, length = radius along it
  Points tangent_v;  // #P by 3 or empty: second tangent axis, length = radius along it
  Colors colors;     // #P by 3 RGB or empty
  // Sharp-crease clip lines (§7, thesis §11.3), both #P by 3 or both empty. A clipped disc keeps the
  // half {y : (y - clip_point) . (normal x clip_dir) >= 0}; a zero clip_dir marks an unclipped surfel.
  Points clip_points;  // #P by 3 or empty: a point of the line, in the surfel's tangent plane
  Points clip_dirs;    // #P by 3 or empty: unit direction of the line (normalised on load), or zero
};

class SurfelModel {
 public:
  SurfelModel() = default;
  // Validates (shapes, finite values, non-zero normals, positive radii), normalises
  // normals, estimates missing radii, and assigns ids 0..#P-1. Throws Error naming the
  // field and row. An empty model is rejected (InvalidArgument).
  static SurfelModel from_arrays(SurfelArrays arrays);
  // A model exactly as saved (snapshots): arrays as they are (not normalised again), `ids` ascending and
  // below `next_id`. Throws InvalidArgument ("snapshot") when shapes or ids do not fit.
  static SurfelModel from_parts(SurfelArrays arrays, IdList ids, SurfelId next_id);

  Index size() const { return static_cast<Index>(a_.positions.rows()); }
  bool empty() const { return size() == 0; }

  const Points& positions() const { return a_.positions; }
  const Points& normals() const { return a_.normals; }
  const Values& radii() const { return a_.radii; }
  const Points& tangent_u() const { return a_.tangent_u; }
  const Points& tangent_v() const { return a_.tangent_v; }
  const Colors& colors() const { return a_.colors; }
  bool has_tangents() const { return a_.tangent_u.rows() == size(); }
  bool has_colors() const { return a_.colors.rows() == size(); }
  const Points& clip_points() const { return a_.clip_points; }
  const Points& clip_dirs() const { return a_.clip_dirs; }
  bool has_clips() const { return a_.clip_dirs.rows() == size() && size() > 0; }
  // Mutable access for in-place updates that keep the row count (deformation).
  SurfelArrays& arrays() { return a_; }
  const SurfelArrays& arrays() const { return a_; }

  // Row -> id (ascending), as a list (built when the ids are 0..size()-1; use id_of() for single rows).
  IdList ids() const;
  // The id of `row` (0 <= row < size()).
  SurfelId id_of(Index row) const { return ids_.empty() ? static_cast<SurfelId>(row) : ids_[static_cast<std::size_t>(row)]; }
  // Id -> row, or -1 if the id is unknown or removed. O(1).
  Index row_of(SurfelId id) const {
    if (ids_.empty()) return id < static_cast<SurfelId>(size()) ? static_cast<Index>(id) : -1;
    return id < next_id_ && alive_.test(static_cast<Index>(id)) ? alive_.rank(static_cast<Index>(id)) : -1;
  }
  // Rows of `ids`; throws NotFound naming `field` and the first unknown id,
  // InvalidArgument on a repeated id.
  IndexList rows_of(const IdList& ids, const std::string& field) const;
  // Next id that insert() will assign.
  SurfelId next_id() const { return next_id_; }

  // Appends validated surfels (same tangents and colors as the model; clip lines may be given or not:
  // missing ones are unclipped); returns their new ids.
  IdList insert(SurfelArrays added);
  // Removes the given ids (validated first: unknown ids throw, nothing changes);
  // the model may not become empty.
  void remove(const IdList& ids);
  // Sets the clip lines of `ids` (#ids by 3 each; a zero direction unclips). Adds the clip arrays
  // (every other surfel unclipped) when the model has none. Validates before changing anything.
  void set_clips(const IdList& ids, const Points& points, const Points& dirs);

  // Content hash over ids, positions, normals and radii (bitwise), and the clip lines when the
  // model has them, for "unchanged" checks.
  std::uint64_t hash() const;
  std::size_t memory_bytes() const;
  // Axis-aligned bounds and their diagonal length.
  Vec3 min_corner() const;
  Vec3 max_corner() const;
  double diagonal() const;

 private:
  // Builds ids_ and alive_ from the identity (before the first removal).
  void spell_out_ids();

  SurfelArrays a_;
  // Row -> id; empty while the ids are the rows (0..size()-1, next_id_ == size(): no surfel was ever removed),
  // which saves 8 bytes per surfel, and 4 more of an id -> row map (issue 14, memory).
  IdList ids_;
  // Once ids_ is spelled out: one bit per id below next_id_, set for the ids in the model; the row of an id is
  // its rank (the ids are ascending), in O(1).
  detail::RankBits alive_;
  SurfelId next_id_ = 0;
};

// Validates arrays as from_arrays() does (without estimating radii). `expect_tangents`,
// `expect_colors`: whether those arrays must be present (nullopt: either).
void validate_arrays(const SurfelArrays& a, std::optional<bool> expect_tangents = std::nullopt,
                     std::optional<bool> expect_colors = std::nullopt);

// Radii from neighbour spacing: per surfel, the mean distance to its k nearest neighbours
// (k = 6), which makes neighbouring discs overlap. A lone surfel gets radius 1.
Values estimate_radii(const Points& positions, int k = 6);

}  // namespace surfeledit
