// The default scene (slab = part 0, sphere = part 1) loaded into an EditSession, and bitwise snapshots
// of what a user observes, for session tests.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {

struct SessionFixture {
  SampledSurfels s = make_default_scene().sample(SampleParams{0.08, 1, 0.25});
  EditSession session{"t"};
  IdList zero, one;  // ids of the slab / the sphere
  explicit SessionFixture(const std::string& author = "") {
    SurfelArrays a;
    a.positions = s.positions;
    a.normals = s.normals;
    a.radii = s.radii;
    session.load(SurfelModel::from_arrays(a), author);
    for (std::size_t i = 0; i < s.part.size(); ++i) (s.part[i] == 0 ? zero : one).push_back(i);
  }
};

// An independent copy of what a user can observe.
struct Snapshot {
  IdList ids;
  Points positions, normals;
  Values radii;
  IdList colliding;
  Points clip_points, clip_dirs;
  std::uint64_t hash = 0;

  explicit Snapshot(const EditSession& s)
      : ids(s.model().ids()),
        positions(s.model().positions()),
        normals(s.model().normals()),
        radii(s.model().radii()),
        colliding(s.colliding()),
        clip_points(s.model().clip_points()),
        clip_dirs(s.model().clip_dirs()),
        hash(s.state_hash()) {}
};

inline void expect_same(const Snapshot& a, const Snapshot& b, const std::string& where) {
  SCOPED_TRACE(where);
  EXPECT_EQ(a.ids, b.ids);
  // Bitwise: Eigen's == compares exactly.
  EXPECT_TRUE(a.positions.rows() == b.positions.rows() && a.positions == b.positions);
  EXPECT_TRUE(a.normals.rows() == b.normals.rows() && a.normals == b.normals);
  EXPECT_TRUE(a.radii.size() == b.radii.size() && a.radii == b.radii);
  EXPECT_EQ(a.colliding, b.colliding);
  EXPECT_TRUE(a.clip_points.rows() == b.clip_points.rows() && a.clip_points == b.clip_points);
  EXPECT_TRUE(a.clip_dirs.rows() == b.clip_dirs.rows() && a.clip_dirs == b.clip_dirs);
  EXPECT_EQ(a.hash, b.hash);
}

// The undo stack of a random sequence: snapshots before each applied op and after each undone one;
// undo() / redo() act on the session and check it against them (false when there is nothing to do).
struct UndoChecker {
  std::vector<Snapshot> before;  // before each applied op (a stack, as the history)
  std::vector<Snapshot> undone;  // after each undone op (the redo tail)

  // An op was applied; `b` is the snapshot from before it.
  void applied(Snapshot b) {
    before.push_back(std::move(b));
    undone.clear();
  }
  bool undo(EditSession& s, const std::string& where) {
    return swap(s, &EditSession::undo, before, undone, "undo at " + where);
  }
  bool redo(EditSession& s, const std::string& where) {
    return swap(s, &EditSession::redo, undone, before, "redo at " + where);
  }

 private:
  static bool swap(EditSession& s, std::uint64_t (EditSession::*op)(), std::vector<Snapshot>& from,
                   std::vector<Snapshot>& to, const std::string& where) {
    if (from.empty()) return false;
    Snapshot now(s);
    (s.*op)();
    expect_same(Snapshot(s), from.back(), where);
    from.pop_back();
    to.push_back(std::move(now));
    return true;
  }
};

}  // namespace surfeledit
