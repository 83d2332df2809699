// A scene: the union of analytic solids (analytic_solids.cpp), its signed distance and its sampling,
// each solid's samples kept only where no other solid contains them (part = the solid's index).
#include "surfeledit/core/scene.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>

namespace surfeledit {

namespace {

// Mixes a seed with a part number so that parts of one scene get independent streams.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t part) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (part + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace

void Scene::add(std::unique_ptr<Solid> solid) {
  if (!solid) throw Error(ErrorCode::InvalidArgument, "solid", "must not be null");
  solids_.push_back(std::move(solid));
}

double Scene::sdf(const Vec3& p) const {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& s : solids_) d = std::min(d, s->sdf(p));
  return d;
}

Values Scene::sdf(const Points& queries, int i) const {
  if (i >= static_cast<int>(solids_.size())) {
    throw Error(ErrorCode::InvalidArgument, "part",
                "part " + std::to_string(i) + " out of range (scene has " + std::to_string(solids_.size()) + ")");
  }
  Values out(queries.rows());
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Vec3 p = queries.row(q).transpose();
    out[q] = i < 0 ? sdf(p) : solids_[static_cast<std::size_t>(i)]->sdf(p);
  }
  return out;
}

SampledSurfels Scene::sample(const SampleParams& params) const {
  std::vector<SampledSurfels> parts;
  Eigen::Index total = 0;
  std::vector<std::vector<char>> keep(solids_.size());
  for (std::size_t i = 0; i < solids_.size(); ++i) {
    SampleParams p = params;
    p.seed = mix_seed(params.seed, i);
    parts.push_back(solids_[i]->sample(p));
    const SampledSurfels& s = parts.back();
    keep[i].assign(static_cast<std::size_t>(s.positions.rows()), 1);
    for (Eigen::Index r = 0; r < s.positions.rows(); ++r) {
      for (std::size_t j = 0; j < solids_.size(); ++j) {
        if (j != i && solids_[j]->sdf(s.positions.row(r).transpose()) < 0.0) {
          keep[i][static_cast<std::size_t>(r)] = 0;
          break;
        }
      }
      total += keep[i][static_cast<std::size_t>(r)];
    }
  }
  SampledSurfels out;
  out.positions.resize(total, 3);
  out.normals.resize(total, 3);
  out.radii.resize(total);
  out.part.reserve(static_cast<std::size_t>(total));
  Eigen::Index o = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    for (Eigen::Index r = 0; r < parts[i].positions.rows(); ++r) {
      if (!keep[i][static_cast<std::size_t>(r)]) continue;
      out.positions.row(o) = parts[i].positions.row(r);
      out.normals.row(o) = parts[i].normals.row(r);
      out.radii[o] = parts[i].radii[r];
      out.part.push_back(static_cast<int>(i));
      ++o;
    }
  }
  return out;
}

Scene make_default_scene() {
  Scene scene;
  // Part 0: rigid slab, 3 x 3 x 0.3 model units, centred at the origin.
  scene.add(make_box(Vec3(1.5, 1.5, 0.15)));
  // Part 1: deformable sphere of radius 0.5 centred at z = 1 (0.35 above the slab's top face).
  Pose above;
  above.translation = Vec3(0.0, 0.0, 1.0);
  scene.add(make_sphere(0.5, above));
  // With the default SampleParams spacing 0.05 the scene has about 9,900 surfels.
  return scene;
}

}  // namespace surfeledit
