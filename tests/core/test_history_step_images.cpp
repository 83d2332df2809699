// A step's before-image at drag sizes (issue 14, the 1M drag): without the normals and tangents of F1 rows
// when the step has no rotation (RowsImage::bent). Truth: the state the session had before the steps, kept
// independently (undo must give it back bit for bit), the state after them (redo), and a one-thread session
// given the same steps (the two-thread one must reach the same bytes). At two threads the image's row copies
// are split between the threads (row_copy.hpp: 150,000 rows of positions and of normals).
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit {
namespace {

// A plate (zero region) of 2,000 surfels under a cloud of 150,000 (the deformation's parallel
// threshold is 50,000 moved rows): the first `one` of them in F1, the rest blend. Random unit normals; with `tangents`,
// random tangent axes too.
struct ImageScene {
  SurfelModel model;
  IdList zero, one;
};

ImageScene make_image_scene(std::size_t one, bool tangents) {
  constexpr std::size_t kZero = 2000, kCloud = 150000;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Index n = static_cast<Eigen::Index>(kZero + kCloud);
  SurfelArrays a;
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  a.radii = Values::Constant(n, 0.01);
  auto unit = [&] {
    Vec3 v(u(rng), u(rng), u(rng));
    while (v.norm() < 0.1) v = Vec3(u(rng), u(rng), u(rng));
    return Vec3(v.normalized());
  };
  ImageScene s;
  for (Eigen::Index i = 0; i < n; ++i) {
    const bool plate = static_cast<std::size_t>(i) < kZero;
    a.positions.row(i) = plate ? Vec3(u(rng), u(rng), -1.0 + 0.01 * u(rng)) : Vec3(u(rng), u(rng), 0.5 + 0.4 * u(rng));
    a.normals.row(i) = unit();
    if (plate) s.zero.push_back(static_cast<SurfelId>(i));
    else if (static_cast<std::size_t>(i) < kZero + one) s.one.push_back(static_cast<SurfelId>(i));
  }
  if (tangents) {
    a.tangent_u.resize(n, 3);
    a.tangent_v.resize(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
      a.tangent_u.row(i) = unit();
      a.tangent_v.row(i) = unit();
    }
  }
  s.model = SurfelModel::from_arrays(a);
  return s;
}

// Every array a step or its undo can change, copied.
struct State {
  Points positions, normals, tangent_u, tangent_v;
  explicit State(const EditSession& s)
      : positions(s.model().positions()),
        normals(s.model().normals()),
        tangent_u(s.model().arrays().tangent_u),
        tangent_v(s.model().arrays().tangent_v) {}
  bool operator==(const State& o) const {
    // Eigen's == is exact (bit for bit but for the sign of zero, which no step here makes).
    return positions == o.positions && normals == o.normals && tangent_u.rows() == o.tangent_u.rows() &&
           tangent_v.rows() == o.tangent_v.rows() && tangent_u == o.tangent_u && tangent_v == o.tangent_v;
  }
};

DeformParams step(double angle) {
  DeformParams p;
  p.translation = Vec3(0.002, -0.001, -0.003);
  p.angle = angle;
  p.axis = Vec3(0.0, 0.6, 0.8);
  return p;
}

std::size_t rows_bytes(const EditSession& s) {
  for (const auto& k : s.report().history_kinds)
    if (k.kind == "rows") return k.bytes;
  return 0;
}

struct StepImageCase {
  std::size_t one;  // F1 rows of the cloud (at least 1; 150,000: all)
  double angle;
  bool tangents;
};

class StepImages : public ::testing::TestWithParam<StepImageCase> {};

TEST_P(StepImages, UndoAfterDragStepsIsBitForBitAtOneAndTwoThreads) {
  const StepImageCase c = GetParam();
  constexpr int kSteps = 4;
  std::vector<State> after_steps;
  for (int threads : {1, 2}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    ImageScene sc = make_image_scene(c.one, c.tangents);
    EditSession s("t", SessionParams{threads});
    s.load(std::move(sc.model));
    s.set_regions({sc.zero, {}}, {sc.one, {}});
    const State original(s);
    std::vector<State> before;
    for (int k = 0; k < kSteps; ++k) {
      before.emplace_back(s);
      s.deform(step(c.angle));
    }
    const State moved(s);
    ASSERT_FALSE(moved == original);
    // Normals of the blend rows changed (the image must keep them), with a rotation every row's; of F1 rows
    // moved without rotation, none.
    EXPECT_EQ(moved.normals == original.normals, c.one == 150000 && c.angle == 0.0);
    after_steps.push_back(moved);
    for (int k = kSteps - 1; k >= 0; --k) {
      s.undo();
      ASSERT_TRUE(State(s) == before[static_cast<std::size_t>(k)]) << "undo of step " << k;
    }
    ASSERT_TRUE(State(s) == original);
    for (int k = 0; k < kSteps; ++k) s.redo();
    EXPECT_TRUE(State(s) == moved);
    s.undo();
    EXPECT_TRUE(State(s) == before.back());
  }
  // The same state at one and two threads.
  EXPECT_TRUE(after_steps[0] == after_steps[1]);
}

// Cloud: all F1 (no normal kept), half F1, one F1 row; without and with a rotation (every normal kept) and
// tangents.
INSTANTIATE_TEST_SUITE_P(Drag, StepImages,
                         ::testing::Values(StepImageCase{150000, 0.0, false}, StepImageCase{75000, 0.0, false}, StepImageCase{75000, 0.0, true},
                                           StepImageCase{1, 0.0, false}, StepImageCase{75000, 0.02, false}, StepImageCase{75000, 0.02, true}));

TEST(StepImages, ATranslationKeepsNoNormalOfF1Rows) {
  // Bytes of one step's image: all F1 without rotation keeps no normal; with a rotation, every normal.
  std::size_t bytes[2] = {0, 0};
  for (int rotate : {0, 1}) {
    ImageScene sc = make_image_scene(150000, false);
    EditSession s("t", SessionParams{2});
    s.load(std::move(sc.model));
    s.set_regions({sc.zero, {}}, {sc.one, {}});
    s.deform(step(rotate ? 0.02 : 0.0));
    bytes[rotate] = rows_bytes(s);
  }
  const std::size_t array = 150000 * 3 * sizeof(double);
  // The rotation's image holds the normals as well (and little else differs: detector states, colliding).
  EXPECT_GE(bytes[1], bytes[0] + array);
  EXPECT_LT(bytes[1], bytes[0] + array + array / 10);
}

TEST(StepImages, ASnapshotKeepsTheBentRows) {
  // Steps without rotation over half F1, saved and restored into a fresh session: undoing them there gives
  // the state before them, as in the session that was saved.
  ImageScene sc = make_image_scene(75000, true);
  EditSession s("t", SessionParams{2});
  s.load(std::move(sc.model));
  s.set_regions({sc.zero, {}}, {sc.one, {}});
  const State original(s);
  for (int k = 0; k < 3; ++k) s.deform(step(0.0));
  SnapshotWriter w;
  s.save(w);
  EditSession copy("t", SessionParams{2});
  SnapshotReader r(w.bytes());
  copy.restore(r);
  for (EditSession* e : {&s, &copy}) {
    for (int k = 0; k < 3; ++k) e->undo();
    EXPECT_TRUE(State(*e) == original);
  }
}

}  // namespace
}  // namespace surfeledit
