// The detector tests' scripted scenarios (the slab and sphere, the concave fold), their scripted edits and
// the runner that plays a script with a detector and the brute-force oracle (collision_oracle.hpp) side by
// side, checking that they agree on every step.
#pragma once

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "collision_oracle.hpp"

namespace surfeledit::testing {

// The scripted scenario of the detector tests: the default scene's slab (zero) and sphere (one
// region = the whole sphere), the sphere pushed down through the slab, turned, pulled back.
inline TestScene slab_and_sphere(double spacing = 0.08) {
  auto slab = make_box(Vec3(1.5, 1.5, 0.15));
  Pose up;
  up.translation = Vec3(0, 0, 1.0);
  auto ball = make_sphere(0.5, up);
  return make_test_scene(*slab, *ball, spacing);
}

// The scripted removal of the detector tests: every 40th zero row and every 11th deformable row
// (from the 6th) leave the scene; `previous` (positions before the step) is compacted alike.
// Returns the kept-row flags for the detectors' on_removed.
inline std::vector<bool> remove_scripted_rows(TestScene& scene, Points& previous) {
  std::vector<bool> keep(scene.rows(), true);
  for (Index r = 0, jd = 0, jz = 0; r < scene.rows(); ++r) {
    if (scene.regions[r] == Region::Zero) {
      if (jz++ % 40 == 39) keep[r] = false;
    } else if (jd++ % 11 == 5) {
      keep[r] = false;
    }
  }
  scene.remove(keep);
  Index j = 0;
  for (Index r = 0; r < previous.rows(); ++r)
    if (keep[r]) previous.row(j++) = previous.row(r);
  previous.conservativeResize(j, 3);
  return keep;
}

struct ScriptStep {
  Vec3 t = Vec3::Zero();
  double angle = 0.0;  // about the x axis through the sphere's current centre
};
inline std::vector<ScriptStep> slab_script() {
  std::vector<ScriptStep> s;
  for (int i = 0; i < 12; ++i) s.push_back({Vec3(0, 0, -0.1), 0.0});
  s.push_back({Vec3(0.05, 0, 0), 0.4});
  s.push_back({Vec3(0, 0.02, 0), -0.3});
  for (int i = 0; i < 4; ++i) s.push_back({Vec3(0, 0, 0.15), 0.0});
  return s;
}

// Fig. 6.4: a plank sampled at `spacing`, its left half rigid (x < 0), a blend band up to x = 0.3 and
// the one region beyond; bend() turns it back by half a turn (over `steps` steps) about the y axis
// through (0, 0, 0.05), just above the seam, so the one region folds into the rigid half.
struct ConcaveFold {
  double spacing = 0.04;
  int steps = 10;
  SampledSurfels s = make_box(Vec3(1.0, 0.3, 0.1))->sample(SampleParams{spacing, 1, 0.25});
  std::vector<Region> regions = regions_of(s.positions);
  DeformationFields fields = compute_fields(s.positions, regions, 1);

  static std::vector<Region> regions_of(const Points& positions) {
    std::vector<Region> out;
    for (Index r = 0; r < positions.rows(); ++r) {
      const double x = positions(r, 0);
      out.push_back(x < 0.0 ? Region::Zero : x > 0.3 ? Region::One : Region::Blend);
    }
    return out;
  }
  // One step of the bend: `pos` and `nrm` (#P by 3) move.
  void bend(Points& pos, Points& nrm) const {
    DeformParams p;
    p.angle = M_PI / steps;
    p.axis = Vec3::UnitY();
    p.center = Vec3(0.0, 0.0, 0.05);
    p.blend = Blend::Linear;
    apply_step(fields, p, pos, nrm);
  }
};

// What one run recorded per step: colliding rows (and their ids, rows' ids being tracked by the test).
struct RunLog {
  std::vector<IndexList> colliding;
  std::vector<std::vector<double>> depths;
  std::vector<CollisionStats> stats;
};

// Detector parameters for algorithm `a` with `threads` worker threads, the rest default.
inline CollisionParams params_of(CollisionAlgorithm a, int threads = 1) {
  CollisionParams p;
  p.algorithm = a;
  p.threads = threads;
  p.parallel_min_ms = 0.0;  // the parallel row loop whenever threads > 1, however small the scene
  return p;
}

// Plays `script` on `scene`: each step moves the deformable part (translation t, turn by `angle` about
// the x axis through its current centroid). With `edits`, at step 4 every 7th deformable row is split
// (a child appended beside it; `inserted(parents)` is called right after) and at step 7
// remove_scripted_rows() removes rows (`removed(keep)` is called right after). Then `step(k, previous)`
// at every step, `previous` being the positions before the step (#P by 3, rows as the scene's now).
template <typename Inserted, typename Removed, typename Step>
void play_script(TestScene& scene, const std::vector<ScriptStep>& script, bool edits, Inserted inserted,
                 Removed removed, Step step) {
  Vec3 centre = Vec3::Zero();
  for (Index r = 0, n = 0; r < scene.rows(); ++r)
    if (scene.regions[r] != Region::Zero) centre += (scene.positions.row(r).transpose() - centre) / ++n;
  for (std::size_t k = 0; k < script.size(); ++k) {
    const Points before = scene.positions;
    scene.move(script[k].t, Eigen::AngleAxisd(script[k].angle, Vec3::UnitX()).toRotationMatrix(), centre);
    centre += script[k].t;
    Points previous = before;
    if (edits && k == 4) {
      IndexList parents;
      for (Index r = 0, j = 0; r < scene.rows(); ++r)
        if (scene.regions[r] != Region::Zero && j++ % 7 == 0) parents.push_back(r);
      for (Index q : parents) scene.append_child(q, 0.3 * scene.radii[q] * Vec3(1, 0, 0).cross(scene.normals.row(q).transpose()));
      previous.conservativeResize(scene.rows(), 3);
      for (std::size_t j = 0; j < parents.size(); ++j) previous.row(before.rows() + j) = previous.row(parents[j]);
      inserted(parents);
    }
    if (edits && k == 7) removed(remove_scripted_rows(scene, previous));
    step(k, previous);
  }
}

// A displacement bound as EditSession hands one over (CollisionScene::displacement_bound): twice the largest
// |p - previous| of a deformable row, by brute force, on a step whose radii are those of the step before (`last`,
// updated here); none otherwise (after a split or a removal).
inline std::optional<double> brute_displacement_bound(const TestScene& scene, const Points& previous, Values& last) {
  const bool same = last.size() == scene.radii.size() && last == scene.radii;
  last = scene.radii;
  if (!same) return std::nullopt;
  double largest = 0.0;
  for (Index r = 0; r < scene.rows(); ++r)
    if (scene.regions[r] != Region::Zero) largest = std::max(largest, (scene.positions.row(r) - previous.row(r)).norm());
  return 2.0 * largest;
}

// Runs `script` on `scene` with the detector and the oracle side by side and checks that they agree on
// every step. With `edits`: at step 4 every 7th deformable row is split (child appended), at step 7
// every 11th deformable row and every 40th zero row are removed. With `bound`, the detector's input carries
// brute_displacement_bound() (the oracle needs none).
inline RunLog run_against_oracle(TestScene scene, const CollisionParams& params, const std::vector<ScriptStep>& script,
                                 bool edits, bool bound = false) {
  std::unique_ptr<CollisionDetector> det = CollisionDetector::create(params);
  Oracle oracle(params);
  det->reset(scene.view());
  oracle.reset(scene);
  RunLog log;
  auto inserted = [&](const IndexList& parents) {
    det->on_inserted(scene.view(), parents);
    oracle.on_inserted(scene, parents);
  };
  auto removed = [&](const std::vector<bool>& keep) {
    det->on_removed(keep);
    oracle.on_removed(keep);
  };
  Values last_radii = scene.radii;
  play_script(scene, script, edits, inserted, removed, [&](std::size_t k, const Points& previous) {
    CollisionScene view = scene.view();
    if (bound) view.displacement_bound = brute_displacement_bound(scene, previous, last_radii);
    const CollisionResult got = det->detect(view, previous);
    std::vector<double> want_depths;
    const IndexList want = oracle.detect(scene, previous, &want_depths);
    EXPECT_EQ(got.colliding, want) << to_string(params.algorithm) << " step " << k;
    if (got.colliding == want) {
      for (std::size_t j = 0; j < want.size(); ++j)
        EXPECT_NEAR(got.depths[j], want_depths[j], 1e-9) << to_string(params.algorithm) << " step " << k;
    }
    EXPECT_EQ(got.stats.colliding, static_cast<Index>(got.colliding.size()));
    if (params.algorithm == CollisionAlgorithm::Robust) EXPECT_EQ(got.stats.queries, oracle.queries);
    log.colliding.push_back(got.colliding);
    log.depths.push_back(got.depths);
    log.stats.push_back(got.stats);
  });
  return log;
}

}  // namespace surfeledit::testing
