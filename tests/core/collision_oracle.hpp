// Test oracle for the collision detectors: a from-scratch, brute-force (no k-d tree) re-implementation
// of each algorithm's definition (docs/algorithms.md §4), and a small mutable scene to script steps on
// (the scripts themselves: collision_scripts.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
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

// Two detectors' results of one step are the same: colliding rows, depths, and the work counted (tested, queries and,
// with `tree_counts`, the hierarchies' nv, np, nu: not when one tree was refit for a step taken back and the
// other's not).
inline void expect_same_detection(const CollisionResult& a, const CollisionResult& b, const std::string& where,
                                  bool tree_counts = true) {
  EXPECT_EQ(a.colliding, b.colliding) << where;
  EXPECT_EQ(a.depths, b.depths) << where;
  EXPECT_EQ(a.stats.tested, b.stats.tested) << where;
  EXPECT_EQ(a.stats.queries, b.stats.queries) << where;
  if (!tree_counts) return;
  EXPECT_EQ(a.stats.nv, b.stats.nv) << where;
  EXPECT_EQ(a.stats.np, b.stats.np) << where;
  EXPECT_EQ(a.stats.nu, b.stats.nu) << where;
}

}  // namespace surfeledit::testing
