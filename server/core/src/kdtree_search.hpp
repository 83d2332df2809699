// Private to the k-d tree's files: its flat layout and its exact descent (docs/algorithms.md §3).
//
// Layout. Points are stored in LEAF ORDER (the order the build left them in) as doubles in the tree's
// local frame, one array per coordinate, so a leaf is one contiguous run of each and a vector scan loads
// consecutive points' x (y, z) at once; no index indirection is followed while scanning it; `rows[slot]`
// maps a slot back to the caller's row. Nodes are in depth-first pre-order: an inner node's left child is
// the next node, its right child is `a`.
//
// Search. The classic incremental-distance descent (Arya & Mount): the squared distance from the query
// to a node's cell is kept per axis and updated on the one axis a cut changes; a far child is visited
// when that lower bound times (1 + eps) is <= the current worst accepted distance (inclusive, so ties are
// never pruned; the bound is summed like a point's distance so rounding cannot lift it above one, and the
// including files, kdtree.cpp and kdtree_avx2.cpp, are compiled without FMA contraction so both sums round
// alike). Ties are broken by the smaller slot, so an exact answer is unique whatever the visiting order: a
// search started from a warm bound returns exactly what a cold one does.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace surfeledit::kd {

inline constexpr std::uint32_t kInner = 0x80000000u;  // Node::b flag of an inner node (its low bits: the axis)
inline constexpr std::uint32_t kFramed = 4u;  // Node::b flag of an inner node that keeps an oriented box (NodeFrame)

// 16 bytes. The cut bounds are floats rounded OUTWARD from the children's extents (lo up, hi down), so a
// cell bound computed from them never exceeds the true one: pruning stays conservative and exact.
struct Node {
  float lo = 0.0f;      // inner: >= the largest coordinate along the axis in the left child
  float hi = 0.0f;      // inner: <= the smallest coordinate along the axis in the right child
  std::uint32_t a = 0;  // inner: index of the right child; leaf: first slot
  std::uint32_t b = 0;  // inner: kInner | axis (0..2); leaf: one past the last slot
  [[gnu::always_inline]] bool leaf() const { return (b & kInner) == 0; }
};

// The k = 1 result: the (dist2, slot)-smallest point with dist2 <= the initial bound.
struct NearestSet {
  double best;                   // dist2 of the current winner, or the (inclusive) start bound
  std::uint32_t slot;            // winner; kNone while there is none
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  explicit NearestSet(double bound2 = std::numeric_limits<double>::infinity()) : best(bound2), slot(kNone) {}
  [[gnu::always_inline]] double worst() const { return best; }
  [[gnu::always_inline]] void add(double d2, std::uint32_t s) {
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
  [[gnu::always_inline]] std::size_t size() const { return n_; }
  [[gnu::always_inline]] double worst() const { return n_ < k_ ? bound_ : d2_[k_ - 1]; }
  [[gnu::always_inline]] void add(double d2, std::uint32_t s) {
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

// How many points have dist2 < r2 (strictly), counted up to `limit`: once there, worst() admits nothing, so the
// descent prunes every node left and the search ends.
struct CountSet {
  double r2;
  std::size_t limit;
  std::size_t n = 0;
  [[gnu::always_inline]] double worst() const { return n < limit ? r2 : -std::numeric_limits<double>::infinity(); }
  [[gnu::always_inline]] void add(double d2, std::uint32_t) { n += (d2 < r2) & (n < limit); }
};

// Every point with dist2 <= r2 (unsorted; the caller sorts).
struct RadiusSet {
  double r2;
  std::vector<std::pair<std::uint32_t, double>>* out;
  [[gnu::always_inline]] double worst() const { return r2; }
  [[gnu::always_inline]] void add(double d2, std::uint32_t s) {
    if (d2 <= r2) push(s, d2);
  }
  // Out of line (kdtree.cpp): the vector's growth is compiled once, for the baseline.
  void push(std::uint32_t s, double d2);
};

// A node's cell for the search that starts from a leaf (nearest_from, kdtree_walk.hpp; only in trees built with
// cells): a box holding every point of the node, and its parent. An inner node's box is the one its ancestors'
// cuts bound it to (the near side of each cut; +-inf where no cut bounds it); a leaf's is also clipped to its
// points' box.
struct Cell {
  float lo[3], hi[3];    // box, local frame
  std::uint32_t parent;  // parent node (the root: itself) | kNoStop
  // Flag in `parent`: the box's faces are not all beyond the points outside the node (a leaf's clipped box, or
  // an inner node under a cut with lo > hi, both children reaching into one float interval), so the search
  // from a leaf cannot stop at this node.
  static constexpr std::uint32_t kNoStop = 0x80000000u;
};

// A fan: what the walk from a leaf (kdtree_walk.hpp) meets over kFanLevels of the tree's levels at once. For an
// inner node R at a depth divisible by kFanLevels, its frontier is the nodes kFanLevels below R, or the leaves
// above that: at most 2^kFanLevels nodes, holding all of R's points. Their cells are kept by coordinate in blocks of
// kFanBlock lanes, so the walk tests them in vectors rather than one cell per level; R's own cell is kept with the
// fan for the walk's stop test. A tree with fans keeps no per-node cells (the walk reads only these).
inline constexpr int kFanLevels = 3;
inline constexpr int kFanLanes = 1 << kFanLevels;
inline constexpr int kFanBlock = 4;
struct alignas(16) FanBlock {
  float lo[3][kFanBlock];  // per axis, each lane's cell (Cell); unused lanes lo = +inf, hi = -inf
  float hi[3][kFanBlock];
  std::uint32_t node[kFanBlock];  // the lane's node; unused lanes 0
};
struct Fan {
  Cell cell;                // R's stop box (kdtree_build.cpp's stop_cells: faces at the far side of each cut); parent 0
  std::uint32_t up = 0;     // R's own lane in its parent fan (Tree::fan_of of R): where the walk goes on; kNoFan at the root
  std::uint32_t first = 0;  // its first block in Tree::fan_blocks (lane k: block first + k / kFanBlock)
  std::uint32_t lanes = 0;  // bit per used lane, in the frontier's pre-order
};

// A fan's halo (kdtree_halos.cpp): the nodes outside the fan's root R that have points in `reach`, a box E around the
// box T of R's points, wider by kHaloReach of T's longest side on every side. Once R's points are searched, a ball
// that E holds (strictly, as the walk's stop test) holds no other point than these nodes' (every point outside E is
// beyond one of its faces), so the walk searches them instead of going on up (kdtree_walk.hpp; RESULTS §76). The
// nodes are leaves, or inner nodes no longer than kHaloCoarse of T; a fan with more than kMaxHalo of them, or none,
// has no halo. Each node's box, clipped to E, is kept in 8-bit codes over E per axis (Halo::value), rounded
// outward: 10 B per node. Clipping is exact for the search: the ball is in E, so what lies outside E is beyond it.
inline constexpr double kHaloReach = 0.5;
inline constexpr double kHaloCoarse = 0.25;
inline constexpr int kHaloBlock = 8;
inline constexpr int kMaxHalo = 64;
struct HaloBlock {
  std::uint8_t lo[3][kHaloBlock];  // per axis, each node's box (codes); unused lanes 0
  std::uint8_t hi[3][kHaloBlock];
  std::uint32_t node[kHaloBlock];  // the node; unused lanes 0
};
struct Halo {
  Cell reach;               // E (floats, rounded outward); parent 0
  std::uint32_t first = 0;  // its first block in Tree::halo_blocks
  std::uint32_t count = 0;  // nodes; 0: no halo
  // Code c's coordinate on axis d: E's lower face plus c steps of 1 / 254 of E's side (so code 254 is E's upper face
  // up to rounding and 255 beyond it); the search computes it with the same operations (no FMA contraction in either
  // file).
  static double step(const Cell& e, int d) {
    return (static_cast<double>(e.hi[d]) - static_cast<double>(e.lo[d])) * (1.0 / 254.0);
  }
  static double value(const Cell& e, int d, int c) {
    return static_cast<double>(e.lo[d]) + static_cast<double>(c) * step(e, d);
  }
};

// A node's oriented box (build_frames; trees built with KdTreeParams::frames): its points' principal axes and
// centroid (floats), and per axis half the extent of the points' projections, widened for rounding. On a tilted surface a node's
// axis-aligned box reaches far into the space beside its points; this box does not, so a search ball that meets
// the first but not the second skips the node (Descent::frame_bound; RESULTS §73). Kept only where it is much
// thinner than the points' axis-aligned box (Tree::frame_of; elsewhere the test is skipped).
struct NodeFrame {
  float c[3];        // centroid, local frame
  float axis[3][3];  // the axes (rows), unit and orthogonal up to float rounding
  float half[3];     // per axis: >= |(p - c) . axis| for every point p of the node, rounding included
};

struct Tree {
  // Points in leaf order, local frame (minus `origin` of the owner), stored by coordinate: x of every slot, then
  // y, then z, each run `stride` = #N + kTail long; the kTail entries past the last slot are zero and only ever
  // read by the masked lanes of a vector scan that starts near the end (kdtree_avx2.cpp).
  static constexpr std::size_t kTail = 8;
  std::vector<double> coords;       // 3 x stride
  std::size_t stride = 0;
  std::vector<std::uint32_t> rows;  // slot -> caller's row
  std::vector<Node> nodes;          // pre-order; nodes[0] is the root when non-empty
  double box_lo[3] = {0, 0, 0}, box_hi[3] = {0, 0, 0};  // bounding box of all points, local frame
  std::vector<Cell> cells;          // per node when built with cells (build_cells) and without fans, else empty
  // Fans for a walk that tests them in vectors (build_fans; empty otherwise), their blocks, and per node the fan it
  // is a frontier node of and its lane (fan * kFanLanes + lane; kNoFan for the root and the nodes inside fans).
  std::vector<Fan> fans;
  std::vector<FanBlock> fan_blocks;
  std::vector<std::uint32_t> fan_of;
  std::vector<Halo> halos;  // per fan (build_fans; Halo::count 0 for a fan without), or empty
  std::vector<HaloBlock> halo_blocks;
  // The oriented boxes kept (build_frames; empty without KdTreeParams::frames), and per node its box's index in them
  // or kNoFrame: most nodes keep none (an upright surface's boxes are already thin), so 4 B per node, not 60.
  std::vector<NodeFrame> frames;
  std::vector<std::uint32_t> frame_of;
  static constexpr std::uint32_t kNoFrame = std::numeric_limits<std::uint32_t>::max();
  static constexpr std::uint32_t kNoFan = std::numeric_limits<std::uint32_t>::max();

  std::size_t size() const { return rows.size(); }
  // The block of fan f that holds its lane `lane`.
  [[gnu::always_inline]] const FanBlock& lane_block(const Fan& f, std::uint32_t lane) const {
    return fan_blocks[f.first + lane / kFanBlock];
  }
  [[gnu::always_inline]] const double* xs() const { return coords.data(); }
  [[gnu::always_inline]] const double* ys() const { return coords.data() + stride; }
  [[gnu::always_inline]] const double* zs() const { return coords.data() + 2 * stride; }

  [[gnu::always_inline]] double dist2(const double* q, std::uint32_t s) const {
    const double dx = q[0] - xs()[s], dy = q[1] - ys()[s], dz = q[2] - zs()[s];
    return dx * dx + dy * dy + dz * dz;
  }
};

// The leaf scan of the baseline build: one point at a time. A vector scan (kdtree_avx2.cpp) computes every
// point's dist2 with the same operations in the same order (no FMA contraction in either file), so the bits and
// hence the winners are the same.
struct ScalarScan {
  // k = 1: the leaf's (dist2, slot)-smallest point first, without a data-dependent branch per point (slots
  // ascend within a leaf, so the first strict minimum is the smallest slot among equals), then one add(): the
  // same lexicographic minimum as adding every point (RESULTS §39). Slots [a, b), a < b.
  static void nearest(const Tree& t, const double* q, std::uint32_t a, std::uint32_t b, NearestSet& set) {
    const double qx = q[0], qy = q[1], qz = q[2];
    const double *X = t.xs(), *Y = t.ys(), *Z = t.zs();
    double bd = t.dist2(q, a);  // the first point seeds the minimum (even an overflowing +inf one)
    std::uint32_t bs = a;
    for (std::uint32_t s = a + 1; s < b; ++s) {
      const double dx = qx - X[s], dy = qy - Y[s], dz = qz - Z[s];
      const double d2 = dx * dx + dy * dy + dz * dz;
      bs = d2 < bd ? s : bs;
      bd = d2 < bd ? d2 : bd;
    }
    set.add(bd, bs);
  }
  // Any other set: every point in slot order.
  template <class Set>
  static void each(const Tree& t, const double* q, std::uint32_t a, std::uint32_t b, Set& set) {
    for (std::uint32_t s = a; s < b; ++s) set.add(t.dist2(q, s), s);
  }
};

// The exact descent over `t` with leaves scanned by `Scan`: feeds `set` every point whose dist2 could beat
// set.worst(); q in the local frame; eps_factor = 1 + eps (1 for exact search). Near child first down to a
// leaf; each far child passed on the way is stacked with its cell bound and visited, latest first, if the bound
// still admits it once the leaf is scanned: the order of the classic recursion, without a call per node and
// with the choice of the near child made without a branch.
template <class Scan, class Set>
class Descent {
 public:
  Descent(const Tree& t, const double* q, Set& set, double eps_factor) : t_(t), q_(q), set_(set), eps_(eps_factor) {}

  void run() {
    if (t_.nodes.empty()) return;
    double off[3];
    box_offsets(t_, q_, off);
    run_from(0, off);
  }

  // The subtree of node `start`, whose points' per-axis squared offsets from q are at least off[0..2].
  void run_from(std::uint32_t start, const double* off) {
    Far cell{start, 0.0, {off[0], off[1], off[2]}};
    cell.d2 = cell.off[0] + cell.off[1] + cell.off[2];
    if constexpr (std::is_same_v<Set, NearestSet>) {
      if (frame_bound(start) > set_.worst()) return;
    }
    const Node* nodes = t_.nodes.data();
    std::size_t depth = 0;
    if (!(cell.d2 * eps_ <= set_.worst())) return;
    for (;;) {
      std::uint32_t ni = cell.node;
      double ox = cell.off[0], oy = cell.off[1], oz = cell.off[2];
      while (!nodes[ni].leaf()) {
        const Node& nd = nodes[ni];
        const std::uint32_t d = nd.b & 3u;
        const double to_left = q_[d] - static_cast<double>(nd.lo);   // > 0: q lies beyond the left child's extent
        const double to_right = static_cast<double>(nd.hi) - q_[d];  // > 0: q lies before the right child's extent
        const bool left_near = to_left < to_right;
        // The far child's gap: to_right when the left child is near, else to_left, i.e. the larger one; its
        // square when positive, else 0 (max(gap, 0)^2 has the same bits as gap > 0 ? gap * gap : 0).
        const double gap = std::max(std::max(to_left, to_right), 0.0);
        Far& f = stack_[depth++];
        f.node = left_near ? nd.a : ni + 1;
        const double cut = gap * gap;
        f.off[0] = d == 0 ? cut : ox;
        f.off[1] = d == 1 ? cut : oy;
        f.off[2] = d == 2 ? cut : oz;
        // Summed afresh, in the leaf's order (x, y, z): every per-axis term is <= the same term of any point
        // in the cell and rounding is monotonic, so the computed bound never exceeds a computed point distance
        // (an incremental mind2 - saved + cut could, by an ulp, and prune a tie).
        f.d2 = f.off[0] + f.off[1] + f.off[2];
        ni = left_near ? ni + 1 : nd.a;
        if constexpr (std::is_same_v<Set, NearestSet>) {
          // The near child too is beyond the best (an inner one with an oriented box: its flag is on this node's
          // line, read next anyway; a leaf is tested below).
          if ((nodes[ni].b & (kInner | kFramed)) == (kInner | kFramed) && frame_bound(ni) > set_.worst()) break;
        }
      }
      const Node& leaf = nodes[ni];
      if constexpr (std::is_same_v<Set, NearestSet>) {
        // A leaf the search starts at was bounded by the caller (its cell) and above (its oriented box).
        if (leaf.leaf() && leaf.a != leaf.b &&
            (ni == start || (leaf_bound(ni) <= set_.worst() && frame_bound(ni) <= set_.worst()))) {
          const std::uint32_t before = set_.slot;
          Scan::nearest(t_, q_, leaf.a, leaf.b, set_);
          won_ = set_.slot != before ? ni : won_;
        }
      } else {
        Scan::each(t_, q_, leaf.a, leaf.b, set_);
      }
      do {
        if (depth == 0) return;
        cell = stack_[--depth];
      } while (!(cell.d2 * eps_ <= set_.worst()) ||
               (std::is_same_v<Set, NearestSet> && frame_bound(cell.node) > set_.worst()));
    }
  }

  // k = 1: the leaf whose scan last changed the winner (the winner's leaf), else kNone.
  std::uint32_t won() const { return won_; }

  // A lower bound of the squared distance from q to the points of leaf `ni`: from its tight box, kept in its cell or,
  // in a tree with fans, in its lane of the fan it is a frontier node of; 0 in a tree with neither.
  double leaf_bound(std::uint32_t ni) const {
    if (!t_.cells.empty()) return box_bound(t_.cells[ni].lo, t_.cells[ni].hi, 1);
    if (t_.fans.empty()) return 0.0;
    const std::uint32_t at = t_.fan_of[ni];
    const FanBlock& b = t_.lane_block(t_.fans[at / kFanLanes], at % kFanLanes);
    return box_bound(&b.lo[0][at % kFanBlock], &b.hi[0][at % kFanBlock], kFanBlock);
  }
  // A lower bound of the computed dist2 of every point of node ni from its oriented box (NodeFrame); 0 without
  // one. Per axis the gap of q's projection beyond the half extent, less the projection's rounding error (a few ulps
  // of |q - c|: 1e-15 of its 1-norm); the float axes are orthonormal only to ~1e-7, so the sum of the squared gaps
  // is at most (1 + 1e-6) |q - p|^2, and it is scaled down by more than that.
  double frame_bound(std::uint32_t ni) const {
    if (t_.frames.empty()) return 0.0;
    const Node& nd = t_.nodes[ni];
    if (!nd.leaf() && !(nd.b & kFramed)) return 0.0;
    const std::uint32_t at = t_.frame_of[ni];
    if (at == Tree::kNoFrame) return 0.0;
    const NodeFrame& f = t_.frames[at];
    const double d[3] = {q_[0] - static_cast<double>(f.c[0]), q_[1] - static_cast<double>(f.c[1]),
                         q_[2] - static_cast<double>(f.c[2])};
    const double slack = 1e-15 * (std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]));
    double b = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double x = d[0] * static_cast<double>(f.axis[k][0]) + d[1] * static_cast<double>(f.axis[k][1]) +
                       d[2] * static_cast<double>(f.axis[k][2]);
      const double g = std::max(std::abs(x) - static_cast<double>(f.half[k]) - slack, 0.0);
      b += g * g;
    }
    return b * (1.0 - 2e-6);
  }
  // The same from a box whose axis d's faces are lo[d * stride] and hi[d * stride].
  double box_bound(const float* lo, const float* hi, int stride) const {
    double d2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      const double g = std::max(
          std::max(static_cast<double>(lo[d * stride]) - q_[d], q_[d] - static_cast<double>(hi[d * stride])), 0.0);
      d2 += g * g;
    }
    return d2;
  }

  // Per axis, the squared offset of q from the tree's box (0 inside it).
  static void box_offsets(const Tree& t, const double* q, double* off) {
    for (int d = 0; d < 3; ++d) {
      const double below = t.box_lo[d] - q[d], above = q[d] - t.box_hi[d];
      off[d] = below > 0.0 ? below * below : (above > 0.0 ? above * above : 0.0);
    }
  }

 private:
  struct Far {
    std::uint32_t node;  // a far child not visited yet
    double d2;           // squared distance from q to its cell (a lower bound of its points')
    double off[3];       // the same per axis
  };
  // A path holds at most 30 Morton cuts (each on a lower code bit than its parent's) and 32 median cuts (each
  // halving a range of equal codes, < 2^32 points): 62 inner nodes, so 64 far children at most.
  static constexpr std::size_t kMaxDepth = 64;

  const Tree& t_;
  const double* q_;
  Set& set_;
  double eps_;
  std::uint32_t won_ = NearestSet::kNone;
  Far stack_[kMaxDepth];
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

// The nearest float >= x / <= x (+-inf beyond float range, which only weakens a bound; the build's boxes).
inline float round_up(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}
inline float round_down(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}

// Sorts (key, value) pairs by the low 30 key bits, stable (LSD radix, 3 passes of 10 bits; kdtree_build.cpp).
void radix_sort(std::vector<std::uint32_t>& key, std::vector<std::uint32_t>& val);

// Builds `t` over the listed `rows` of `points` (row-major #P by 3, world units), stored relative to
// `origin`; lo / hi: their bounding box in that local frame (3 each). Points are sorted along a Morton
// curve and every cell is cut at its midpoint (kdtree_build.cpp). Leaves hold at most `leaf` points (more
// only when all of them coincide).
void build(Tree& t, const double* points, std::vector<std::uint32_t> rows, const double* origin, const double* lo,
           const double* hi, std::uint32_t leaf);
// Fills t.cells (one per node) for nearest_from (kdtree_build.cpp).
void build_cells(Tree& t);
// A turned frame is kept when the box of the points along it has under this share of their axis-aligned box's volume
// (KdTreeParams::align): a clearly better fit, since a turned frame costs each query a product with it and rounds
// its distances differently.
inline constexpr double kTurnedVolume = 0.7;
// A box's volume from its corners, each side taken as at least 1e-3 of the longest: a flat or linear point set still
// compares by its other sides, and an exactly flat one is not infinitely better than a nearly flat one.
double floored_volume(const double lo[3], const double hi[3]);
// Axes along which the surfaces of the listed `rows` of `points` (world units; `origin`: their centroid) lie, as the
// rows of `turn`: those along which the coordinates of a fixed-seed sample are the most concentrated (a flat
// part's points along its normal fall into few bins), found about the sample's principal axes; false (turn untouched)
// when the world axes are as good. The caller keeps them only when the points' box along them is under kTurnedVolume
// of the axis-aligned box (kdtree_align.cpp).
bool choose_turn(const double* points, const std::vector<std::uint32_t>& rows, const double* origin, double turn[3][3]);
// Fills t.frames and t.frame_of from the points (kdtree_frames.cpp).
void build_frames(Tree& t);
// Fills t.halos and t.halo_blocks for the fans whose roots are `roots`, from t.cells (kdtree_halos.cpp).
void build_halos(Tree& t, const std::vector<std::uint32_t>& roots);
// Fills t.fans, t.fan_blocks, t.fan_of and the fans' halos from t.cells, then drops the cells (kdtree_build.cpp). A tree without an
// inner node gets no fans and keeps its cells.
void build_fans(Tree& t);

}  // namespace surfeledit::kd
