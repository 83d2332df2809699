// A step's `previous` (the positions before it, each surfel's own displacement for the detector: the step
// bound, the swept test). After the tool's own step only its deformable rows are brought up to date, in the
// before-image's pass (EditSession::deform); any other change to the session makes a whole copy. Truth: the
// same steps with an undo and a redo after each (the session as it was, at a new version: every step then
// copies the whole model), step by step the same colliding ids and depths, bit for bit.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "session_fixture.hpp"
#include "surfeledit/core/edit_session.hpp"

namespace surfeledit {
namespace {

DeformParams through(int k) {
  DeformParams p;
  p.translation = Vec3(0.01 * (k % 3 - 1), 0.0, -0.16);
  p.angle = k % 2 ? 0.0 : 0.03;  // with and without rotation (the finite check's two paths)
  p.axis = Vec3(1, 0, 0);
  return p;
}

TEST(StepPrevious, OwnStepsGiveTheResultsOfWholeCopies) {
  const std::vector<std::vector<NamedSetting>> configs = {
      {{"algorithm", std::string("temporal")}, {"swept", true}},
      {{"algorithm", std::string("temporal")}},
      {{"algorithm", std::string("simple")}},
      {{"algorithm", std::string("robust")}},
  };
  for (std::size_t c = 0; c < configs.size(); ++c) {
    SCOPED_TRACE("config " + std::to_string(c));
    SessionFixture a, b;
    for (SessionFixture* f : {&a, &b}) {
      f->session.set_regions({f->zero, {}}, {f->one, {}});
      f->session.configure(configs[c]);
    }
    int collided = 0;
    for (int k = 0; k < 9; ++k) {
      SCOPED_TRACE("step " + std::to_string(k));
      const StepResult ra = a.session.deform(through(k));
      const StepResult rb = b.session.deform(through(k));
      b.session.undo();
      b.session.redo();
      EXPECT_EQ(ra.colliding, rb.colliding);
      EXPECT_EQ(ra.depths, rb.depths);
      EXPECT_EQ(ra.stats.queries, rb.stats.queries);
      expect_same(Snapshot(a.session), Snapshot(b.session), "after the step");
      collided += !ra.colliding.empty();
    }
    EXPECT_GE(collided, 3) << "the sphere should pass into the slab";
  }
}

}  // namespace
}  // namespace surfeledit
