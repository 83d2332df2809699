// Private to kdtree.cpp: the k-d tree's flat layout and its exact descent (docs/algorithms.md §3).
//
// Layout. Points are stored in LEAF ORDER (the order the build left them in), packed x y z doubles in
// the tree's local frame, so a leaf is one contiguous run of memory and no index indirection is
// followed while scanning it; `rows[slot]` maps a slot back to the caller's row. Nodes are in depth-first
// pre-order: an inner node's left child is the next node, its right child is `a`.
//
// Search. The classic incremental-distance descent (Arya & Mount): the squared distance from the query
// to a node's cell is kept per axis and updated on the one axis a cut changes; a far child is visited
// when that lower bound times (1 + eps) is <= the current worst accepted distance (inclusive, so ties are
// never pruned; the bound is summed like a point's distance so rounding cannot lift it above one, and the
// including file, kdtree.cpp, is compiled without FMA contraction so both sums round alike). Ties are
// broken by the smaller slot, so an exact answer is unique whatever the visiting order: a search started
// from a warm bound returns exactly what a cold one does.
#pragma once

#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace surfeledit::kd {

inline constexpr std::uint32_t kInner = 0x80000000u;  // Node::b flag of an inner node (its low bits: the axis)

// 16 bytes. The cut bounds are floats rounded OUTWARD from the children's extents (lo up, hi down), so a
// cell bound computed from them never exceeds the true one: pruning stays conservative and exact.
struct Node {
  float lo = 0.0f;      // inner: >= the largest coordinate along the axis in the left child
  float hi = 0.0f;      // inner: <= the smallest coordinate along the axis in the right child
  std::uint32_t a = 0;  // inner: index of the right child; leaf: first slot
  std::uint32_t b = 0;  // inner: kInner | axis (0..2); leaf: one past the last slot
  bool leaf() const { return (b & kInner) == 0; }
};

// The k = 1 result: the (dist2, slot)-smallest point with dist2 <= the initial bound.
struct NearestSet {
  double best;                   // dist2 of the current winner, or the (inclusive) start bound
  std::uint32_t slot;            // winner; kNone while there is none
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  explicit NearestSet(double bound2 = std::numeric_limits<double>::infinity()) : best(bound2), slot(kNone) {}
  double worst() const { return best; }
  void add(double d2, std::uint32_t s) {
    if (d2 < best || (d2 == best && s < slot)) {
      best = d2;
      slot = s;
    }
  }
};

// The k (dist2, slot)-smallest points with dist2 <= the initial bound, ascending (insertion into k slots).
class KnnSet {
 public:
  KnnSet(std::size_t k, std::uint32_t* slots, double* d2, double bound2 = std::numeric_limits<double>::infinity())
      : k_(k), slots_(slots), d2_(d2), bound_(bound2) {}
  std::size_t size() const { return n_; }
  double worst() const { return n_ < k_ ? bound_ : d2_[k_ - 1]; }
  void add(double d2, std::uint32_t s) {
    if (n_ == k_ && !(d2 < d2_[k_ - 1] || (d2 == d2_[k_ - 1] && s < slots_[k_ - 1]))) return;
    if (n_ < k_ && d2 > bound_) return;
    std::size_t j = n_ < k_ ? n_++ : k_ - 1;
    for (; j > 0 && (d2_[j - 1] > d2 || (d2_[j - 1] == d2 && slots_[j - 1] > s)); --j) {
      d2_[j] = d2_[j - 1];
      slots_[j] = slots_[j - 1];
    }
    d2_[j] = d2;
    slots_[j] = s;
  }

 private:
  std::size_t k_, n_ = 0;
  std::uint32_t* slots_;
  double* d2_;
  double bound_;
};

// Every point with dist2 <= r2 (unsorted; the caller sorts).
struct RadiusSet {
  double r2;
  std::vector<std::pair<std::uint32_t, double>>* out;
  double worst() const { return r2; }
  void add(double d2, std::uint32_t s) {
    if (d2 <= r2) out->emplace_back(s, d2);
  }
};

struct Tree {
  std::vector<double> xyz;          // 3 x #N, leaf order, local frame (minus `origin` of the owner)
  std::vector<std::uint32_t> rows;  // slot -> caller's row
  std::vector<Node> nodes;          // pre-order; nodes[0] is the root when non-empty
  double box_lo[3] = {0, 0, 0}, box_hi[3] = {0, 0, 0};  // bounding box of all points, local frame

  std::size_t size() const { return rows.size(); }

  double dist2(const double* q, std::uint32_t s) const {
    const double* p = &xyz[3 * static_cast<std::size_t>(s)];
    const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
    return dx * dx + dy * dy + dz * dz;
  }

  // Feeds `set` every point whose dist2 could beat set.worst(); q in the local frame.
  // eps_factor = 1 + eps (1 for exact search).
  template <class Set>
  void search(const double* q, Set& set, double eps_factor) const {
    if (nodes.empty()) return;
    double off[3];
    for (int d = 0; d < 3; ++d) {
      const double below = box_lo[d] - q[d], above = q[d] - box_hi[d];
      off[d] = below > 0.0 ? below * below : (above > 0.0 ? above * above : 0.0);
    }
    const double mind2 = off[0] + off[1] + off[2];
    if (mind2 * eps_factor <= set.worst()) descend(0, q, off, set, eps_factor);
  }

 private:
  template <class Set>
  void descend(std::uint32_t ni, const double* q, double* off, Set& set, double eps_factor) const {
    const Node& nd = nodes[ni];
    if (nd.leaf()) {
      const double qx = q[0], qy = q[1], qz = q[2];
      const double* p = &xyz[3 * static_cast<std::size_t>(nd.a)];
      if constexpr (std::is_same_v<Set, NearestSet>) {
        // k = 1: the leaf's (dist2, slot)-smallest point first, without a data-dependent branch per point
        // (slots ascend within a leaf, so the first strict minimum is the smallest slot among equals),
        // then one add(): the same lexicographic minimum as adding every point (RESULTS §39).
        if (nd.a == nd.b) return;
        double bd = dist2(q, nd.a);  // the first point seeds the minimum (even an overflowing +inf one)
        std::uint32_t bs = nd.a;
        p += 3;
        for (std::uint32_t s = nd.a + 1; s < nd.b; ++s, p += 3) {
          const double dx = qx - p[0], dy = qy - p[1], dz = qz - p[2];
          const double d2 = dx * dx + dy * dy + dz * dz;
          bs = d2 < bd ? s : bs;
          bd = d2 < bd ? d2 : bd;
        }
        set.add(bd, bs);
        return;
      }
      for (std::uint32_t s = nd.a; s < nd.b; ++s, p += 3) {
        const double dx = qx - p[0], dy = qy - p[1], dz = qz - p[2];
        set.add(dx * dx + dy * dy + dz * dz, s);
      }
      return;
    }
    const std::uint32_t d = nd.b & 3u;
    const double to_left = q[d] - static_cast<double>(nd.lo);   // > 0: q lies beyond the left child's extent
    const double to_right = static_cast<double>(nd.hi) - q[d];  // > 0: q lies before the right child's extent
    std::uint32_t near, far;
    double cut;
    if (to_left < to_right) {  // nearer the left child
      near = ni + 1;
      far = nd.a;
      cut = to_right > 0.0 ? to_right * to_right : 0.0;
    } else {
      near = nd.a;
      far = ni + 1;
      cut = to_left > 0.0 ? to_left * to_left : 0.0;
    }
    descend(near, q, off, set, eps_factor);
    const double saved = off[d];
    off[d] = cut;
    // Summed afresh, in the leaf's order (x, y, z): every per-axis term is <= the same term of any point
    // in the cell and rounding is monotonic, so the computed bound never exceeds a computed point distance
    // (an incremental mind2 - saved + cut could, by an ulp, and prune a tie).
    const double far_d2 = off[0] + off[1] + off[2];
    if (far_d2 * eps_factor <= set.worst()) descend(far, q, off, set, eps_factor);
    off[d] = saved;
  }
};

// Spreads the low 10 bits of v to every third bit (Morton interleave: x, y, z codes -> one 30-bit code).
inline std::uint32_t spread10(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// Sorts (key, value) pairs by the low 30 key bits, stable (LSD radix, 3 passes of 10 bits; kdtree_build.cpp).
void radix_sort(std::vector<std::uint32_t>& key, std::vector<std::uint32_t>& val);

// Builds `t` over the listed `rows` of `points` (row-major #P by 3, world units), stored relative to
// `origin`; lo / hi: their bounding box in that local frame (3 each). Points are sorted along a Morton
// curve and every cell is cut at its midpoint (kdtree_build.cpp). Leaves hold at most `leaf` points (more
// only when all of them coincide).
void build(Tree& t, const double* points, std::vector<std::uint32_t> rows, const double* origin, const double* lo,
           const double* hi, std::uint32_t leaf);

}  // namespace surfeledit::kd
