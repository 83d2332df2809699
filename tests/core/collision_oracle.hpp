// Test oracle for the collision detectors: a from-scratch, brute-force (no k-d tree) re-implementation
// of each algorithm's definition (docs/algorithms.md §4), and a small mutable scene to script steps on.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"

#include <Eigen/Geometry>

namespace surfeledit::testing {

// A model the tests move by hand: #P rows of everything.
struct TestScene {
  Points positions, normals;
  Values radii;
  std::vector<Region> regions;
  CollisionScene view() const { return CollisionScene{positions, normals, radii, regions}; }
  Index rows() const { return static_cast<Index>(positions.rows()); }

  // Moves every deformable row rigidly: p -> R (p - c) + c + t.
  void move(const Vec3& t, const Mat3& rot = Mat3::Identity(), const Vec3& c = Vec3::Zero()) {
    for (Index r = 0; r < rows(); ++r) {
      if (regions[r] == Region::Zero) continue;
      positions.row(r) = (rot * (positions.row(r).transpose() - c) + c + t).transpose();
      normals.row(r) = (rot * normals.row(r).transpose()).transpose();
    }
  }
  // Appends a copy of row `parent` shifted by `offset` (a split child).
  void append_child(Index parent, const Vec3& offset) {
    const Index n = rows();
    positions.conservativeResize(n + 1, 3);
    normals.conservativeResize(n + 1, 3);
    radii.conservativeResize(n + 1);
    positions.row(n) = positions.row(parent) + offset.transpose();
    normals.row(n) = normals.row(parent);
    radii[n] = radii[parent];
    regions.push_back(regions[parent]);
  }
  void remove(const std::vector<bool>& keep) {
    Index j = 0;
    for (Index r = 0; r < rows(); ++r) {
      if (!keep[r]) continue;
      positions.row(j) = positions.row(r);
      normals.row(j) = normals.row(r);
      radii[j] = radii[r];
      regions[j] = regions[r];
      ++j;
    }
    positions.conservativeResize(j, 3);
    normals.conservativeResize(j, 3);
    radii.conservativeResize(j);
    regions.resize(j);
  }
};

// A lone solid pair: `zero_solid` sampled as the rigid part, `deformable_solid` as the moving one.
inline TestScene make_test_scene(const Solid& zero_solid, const Solid& deformable_solid, double spacing) {
  const SampledSurfels z = zero_solid.sample(SampleParams{spacing, 1, 0.25});
  const SampledSurfels d = deformable_solid.sample(SampleParams{spacing, 2, 0.25});
  TestScene t;
  const Index nz = static_cast<Index>(z.positions.rows()), nd = static_cast<Index>(d.positions.rows());
  t.positions.resize(nz + nd, 3);
  t.normals.resize(nz + nd, 3);
  t.radii.resize(nz + nd);
  t.positions << z.positions, d.positions;
  t.normals << z.normals, d.normals;
  t.radii << z.radii, d.radii;
  t.regions.assign(static_cast<std::size_t>(nz), Region::Zero);
  t.regions.resize(static_cast<std::size_t>(nz + nd), Region::One);
  return t;
}

// Brute-force nearest among `candidates` (smallest squared distance, ties: lowest index).
inline Index brute_nearest(const Points& p, const std::vector<Index>& candidates, const Vec3& q) {
  Index best = -1;
  double best2 = std::numeric_limits<double>::infinity();
  for (Index c : candidates) {
    const double d2 = (q - p.row(c).transpose()).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best = c;
    }
  }
  return best;
}

// The slow reference. Per-row state vectors; everything recomputed by brute force.
class Oracle {
 public:
  explicit Oracle(CollisionParams params) : p_(params) {}

  void reset(const TestScene& s) {
    const Index n = s.rows();
    colliding_.assign(n, false);
    marked_.assign(n, false);
    first_.assign(n, true);
    inside_.assign(n, false);
    center_ = s.positions;
    old_ = s.positions;
    rho2_.assign(n, 0.0);
    depth_.assign(n, 0.0);
    mean_dist2_ = 0.0;
    const std::vector<Index> zero = zero_rows(s);
    // Boundary marks: each deformable surfel's n nearest others; their i nearest zero surfels.
    if (p_.boundary) {
      for (Index r = 0; r < n; ++r) {
        if (s.regions[r] == Region::Zero) continue;
        std::vector<std::pair<double, Index>> all;
        for (Index o = 0; o < n; ++o)
          if (o != r) all.push_back({(s.positions.row(o) - s.positions.row(r)).squaredNorm(), o});
        std::sort(all.begin(), all.end());
        int marks = 0;
        for (int j = 0; j < p_.boundary_n && j < static_cast<int>(all.size()) && marks < p_.boundary_i; ++j) {
          if (s.regions[all[j].second] == Region::Zero) {
            marked_[all[j].second] = true;
            ++marks;
          }
        }
      }
    }
    for (Index r = 0; r < n; ++r) {
      if (s.regions[r] == Region::Zero) continue;
      const Vec3 p = s.positions.row(r).transpose();
      const Index k = brute_nearest(s.positions, zero, p);
      rho2_[r] = shrunk((p - s.positions.row(k).transpose()).squaredNorm(), s.radii[k]);
    }
    orig_pos_ = s.positions;
    orig_nrm_ = s.normals;
    orig_rad_ = s.radii;
    orig_zero_.clear();
    for (Region g : s.regions) orig_zero_.push_back(g == Region::Zero);
    orig_alive_.assign(n, true);
    orig_of_row_.resize(n);
    for (Index r = 0; r < n; ++r) orig_of_row_[r] = r;
  }

  // Rows colliding after the step, ascending; `depths` per colliding row.
  IndexList detect(const TestScene& s, const Points& previous, std::vector<double>* depths = nullptr) {
    const std::vector<Index> zero = zero_rows(s);
    switch (p_.algorithm) {
      case CollisionAlgorithm::Simple:
        for (Index r = 0; r < s.rows(); ++r)
          if (s.regions[r] != Region::Zero) simple(s, previous, zero, r);
        break;
      case CollisionAlgorithm::Improved: improved(s, previous, zero); break;
      case CollisionAlgorithm::Temporal:
        for (Index r = 0; r < s.rows(); ++r) {
          if (s.regions[r] == Region::Zero) continue;
          const Vec3 p = s.positions.row(r).transpose();
          const double m2 = (p - center_.row(r).transpose()).squaredNorm();
          if (m2 < rho2_[r]) {
            depth_[r] = std::max(0.0, std::sqrt(rho2_[r]) - std::sqrt(m2));
            continue;
          }
          const double d2 = simple(s, previous, zero, r);
          center_.row(r) = p.transpose();
          rho2_[r] = shrunk(d2, s.radii[last_nearest_]);
        }
        break;
      case CollisionAlgorithm::Robust: robust(s); break;
      default: break;
    }
    IndexList out;
    for (Index r = 0; r < s.rows(); ++r) {
      if (s.regions[r] == Region::Zero || !colliding_[r]) continue;
      out.push_back(r);
      if (depths) depths->push_back(depth_[r]);
    }
    return out;
  }

  void on_removed(const std::vector<bool>& keep) {
    for (std::size_t r = 0; r < keep.size(); ++r)
      if (!keep[r] && orig_of_row_[r] >= 0 && orig_zero_[orig_of_row_[r]]) orig_alive_[orig_of_row_[r]] = false;
    auto squeeze = [&](auto& v) {
      std::size_t j = 0;
      for (std::size_t r = 0; r < keep.size(); ++r)
        if (keep[r]) v[j++] = v[r];
      v.resize(j);
    };
    squeeze(colliding_);
    squeeze(marked_);
    squeeze(first_);
    squeeze(inside_);
    squeeze(rho2_);
    squeeze(depth_);
    squeeze(orig_of_row_);
    Points c(0, 3), o(0, 3);
    for (std::size_t r = 0; r < keep.size(); ++r) {
      if (!keep[r]) continue;
      c.conservativeResize(c.rows() + 1, 3);
      c.row(c.rows() - 1) = center_.row(r);
      o.conservativeResize(o.rows() + 1, 3);
      o.row(o.rows() - 1) = old_.row(r);
    }
    center_ = c;
    old_ = o;
  }

  void on_inserted(const TestScene& s, const IndexList& parents) {
    const Index base = s.rows() - static_cast<Index>(parents.size());
    center_.conservativeResize(s.rows(), 3);
    old_.conservativeResize(s.rows(), 3);
    for (std::size_t k = 0; k < parents.size(); ++k) {
      const Index q = parents[k], b = base + static_cast<Index>(k);
      colliding_.push_back(colliding_[q]);
      marked_.push_back(false);
      first_.push_back(first_[q]);
      inside_.push_back(inside_[q]);
      depth_.push_back(depth_[q]);
      orig_of_row_.push_back(-1);
      old_.row(b) = old_.row(q);
      const Vec3 pb = s.positions.row(b).transpose();
      if ((pb - center_.row(q).transpose()).squaredNorm() < rho2_[q]) {
        center_.row(b) = center_.row(q);
        rho2_.push_back(rho2_[q]);
      } else {
        center_.row(b) = pb.transpose();
        rho2_.push_back(0.0);
      }
    }
    for (Index q : parents) {
      const Vec3 pa = s.positions.row(q).transpose();
      if (!((pa - center_.row(q).transpose()).squaredNorm() < rho2_[q])) {
        center_.row(q) = pa.transpose();
        rho2_[q] = 0.0;
      }
    }
  }

  Index queries = 0;  // nearest-neighbour queries of the last detect()

 private:
  static std::vector<Index> zero_rows(const TestScene& s) {
    std::vector<Index> z;
    for (Index r = 0; r < s.rows(); ++r)
      if (s.regions[r] == Region::Zero) z.push_back(r);
    return z;
  }

  // §4.1 for row r; returns |d|^2 to its nearest zero surfel.
  double simple(const TestScene& s, const Points& previous, const std::vector<Index>& zero, Index r) {
    const Vec3 p1 = s.positions.row(r).transpose();
    const Index k = brute_nearest(s.positions, zero, p1);
    last_nearest_ = k;
    const Vec3 d = p1 - s.positions.row(k).transpose();
    const double d2 = d.squaredNorm();
    depth_[r] = std::sqrt(d2);
    if (p_.step_bound) {
      const double t = (p1 - previous.row(r).transpose()).norm();
      const double bound = t + s.radii[r] + s.radii[k];
      if (d2 > bound * bound) return d2;  // keeps its state
    }
    const bool inside = d.dot(s.normals.row(k).transpose()) < p_.threshold;
    colliding_[r] = inside && !(p_.boundary && marked_[k]);
    return d2;
  }

  void improved(const TestScene& s, const Points& previous, const std::vector<Index>& zero) {
    std::vector<bool> settled(s.rows(), false);
    double sum = 0.0;
    Index tested = 0;
    for (Index r = 0; r < s.rows(); ++r) {
      if (s.regions[r] == Region::Zero || settled[r]) continue;
      const double d2 = simple(s, previous, zero, r);
      settled[r] = true;
      sum += d2;
      ++tested;
      if (!(d2 > mean_dist2_)) continue;
      for (Index j = 0; j < s.rows(); ++j) {
        if (s.regions[j] == Region::Zero || settled[j]) continue;
        const double e2 = (s.positions.row(j) - s.positions.row(r)).squaredNorm();
        if (e2 < d2) {
          settled[j] = true;
          colliding_[j] = colliding_[r];
          depth_[j] = std::sqrt(d2) - std::sqrt(e2);
        }
      }
    }
    mean_dist2_ = tested ? sum / tested : 0.0;
  }

  // Code 6.8, literally.
  void robust(const TestScene& s) {
    std::vector<Index> orig;
    for (std::size_t o = 0; o < orig_alive_.size(); ++o)
      if (orig_alive_[o]) orig.push_back(static_cast<Index>(o));
    queries = 0;
    for (Index r = 0; r < s.rows(); ++r) {
      if (s.regions[r] == Region::Zero) continue;
      const Vec3 p1 = s.positions.row(r).transpose();
      if ((p1 - center_.row(r).transpose()).squaredNorm() >= rho2_[r]) {
        if (first_[r]) {
          first_[r] = false;
          const Vec3 old = old_.row(r).transpose();
          const Index k = brute_nearest(orig_pos_, orig, old);
          ++queries;
          inside_[r] = (old - orig_pos_.row(k).transpose()).dot(orig_nrm_.row(k).transpose()) < p_.threshold;
        }
        const Index k = brute_nearest(orig_pos_, orig, p1);
        ++queries;
        center_.row(r) = p1.transpose();
        rho2_[r] = shrunk((p1 - orig_pos_.row(k).transpose()).squaredNorm(), orig_rad_[k]);
        const bool now = (p1 - orig_pos_.row(k).transpose()).dot(orig_nrm_.row(k).transpose()) < p_.threshold;
        if (orig_zero_[k] && now != inside_[r]) colliding_[r] = !colliding_[r];
        inside_[r] = now;
      }
      if (colliding_[r]) {
        depth_[r] = std::max(0.0, std::sqrt(rho2_[r]) - (p1 - center_.row(r).transpose()).norm());
      } else {
        old_.row(r) = p1.transpose();
      }
    }
  }

  CollisionParams p_;
  std::vector<bool> colliding_, marked_, first_, inside_;
  Points center_, old_;
  std::vector<double> rho2_, depth_;
  double mean_dist2_ = 0.0;
  Points orig_pos_, orig_nrm_;
  Values orig_rad_;
  Index last_nearest_ = -1;  // zero surfel found by the last simple() test

  // Sphere radius^2 of the definition: (|d| - sphere_margin * r2)^2, 0 when not positive.
  double shrunk(double d2, double r2) const {
    if (p_.sphere_margin == 0.0) return d2;
    const double rho = std::sqrt(d2) - p_.sphere_margin * r2;
    return rho > 0.0 ? rho * rho : 0.0;
  }
  std::vector<bool> orig_zero_, orig_alive_;
  std::vector<Index> orig_of_row_;
};

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

// Runs `script` on `scene` with the detector and the oracle side by side and checks that they agree on
// every step. With `edits`: at step 4 every 7th deformable row is split (child appended), at step 7
// every 11th deformable row and every 40th zero row are removed.
inline RunLog run_against_oracle(TestScene scene, const CollisionParams& params, const std::vector<ScriptStep>& script,
                                 bool edits) {
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
  play_script(scene, script, edits, inserted, removed, [&](std::size_t k, const Points& previous) {
    const CollisionResult got = det->detect(scene.view(), previous);
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
