// Inside/outside classification of query points against a closed surfel model (docs/algorithms.md §2).
//
//   p1 is inside  <=>  (p1 - p2) . n2 <= W
// with p2, n2 the position and normal of the surfel nearest to p1.
#pragma once

#include <memory>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {

struct InsideOutsideParams {
  double threshold = 0.0;  // W, in model units; W > 0 also counts points within W outside the surface
  int threads = 0;         // worker threads for batch classification; 0 = all
};

class InsideOutside {
 public:
  // `positions`, `normals`: #P by 3 (normals unit, outward). Copies what it needs.
  InsideOutside(const Points& positions, const Points& normals, KdTreeParams tree = {});

  // One query. `nearest` (optional) receives the index of the nearest surfel,
  // `signed_offset` (optional) the value (p1 - p2) . n2.
  bool inside(const Vec3& q, double threshold, Index* nearest = nullptr,
              double* signed_offset = nullptr) const;
  // #Q queries -> #Q flags (1 inside, 0 outside).
  std::vector<std::uint8_t> classify(const Points& queries, InsideOutsideParams params = {}) const;

  const KdTree& tree() const;

 private:
  Points normals_;
  KdTree tree_;
  Points positions_;
};

// One-shot helper: builds the tree and classifies.
std::vector<std::uint8_t> classify_inside(const Points& positions, const Points& normals,
                                          const Points& queries, InsideOutsideParams params = {});

}  // namespace surfeledit
