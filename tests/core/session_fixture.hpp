// The default scene (slab = part 0, sphere = part 1) loaded into an EditSession, for session tests.
#pragma once

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

}  // namespace surfeledit
