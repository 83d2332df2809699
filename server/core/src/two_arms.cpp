#include "surfeledit/core/two_arms.hpp"

#include <algorithm>

namespace surfeledit {

namespace {

Pose at(const Vec3& c) {
  Pose p;
  p.translation = c;
  return p;
}

}  // namespace

TwoArms::TwoArms(const SampleParams& params) {
  Scene scene;
  scene.add(body_solid());
  scene.add(arm_a_solid());
  scene.add(arm_b_solid());
  surfels = scene.sample(params);
  for (std::size_t i = 0; i < surfels.part.size(); ++i) {
    const SurfelId id = static_cast<SurfelId>(i);
    (surfels.part[i] == 0 ? body : surfels.part[i] == 1 ? a : b).push_back(id);
  }
}

SurfelModel TwoArms::model() const {
  SurfelArrays m;
  m.positions = surfels.positions;
  m.normals = surfels.normals;
  m.radii = surfels.radii;
  return SurfelModel::from_arrays(m);
}

std::unique_ptr<Solid> TwoArms::body_solid() { return make_box(body_half()); }

std::unique_ptr<Solid> TwoArms::arm_a_solid(const Vec3& offset) {
  return make_capsule(kArmRadius, kArmHalf, at(Vec3(-kArmX, 0, kArmZ) + offset));
}

std::unique_ptr<Solid> TwoArms::arm_b_solid(const Vec3& offset) {
  return make_capsule(kArmRadius, kArmHalf, at(Vec3(kArmX, 0, kArmZ) + offset));
}

IdList TwoArms::join(IdList x, const IdList& y) {
  x.insert(x.end(), y.begin(), y.end());
  std::sort(x.begin(), x.end());
  return x;
}

}  // namespace surfeledit
