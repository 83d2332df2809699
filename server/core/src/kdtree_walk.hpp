// Private to the k-d tree's files: the exact nearest search that starts from a leaf (a tree built with cells,
// kdtree_search.hpp's Cell) and walks up through the leaf's ancestors, and the table of search entries a tree's
// owner picks once (kdtree.cpp).
#pragma once

#include "kdtree_search.hpp"

namespace surfeledit::kd {

// The walk's two box tests per level, one axis at a time (the baseline build; kdtree_avx2.cpp has a vector
// version with the same operations, hence the same bits). `q`: the query, local frame; `box`: per axis, the
// squared offset of q from the tree's box (Descent::box_offsets).
class ScalarWalk {
 public:
  static constexpr bool kFans = false;  // climbs one level at a time
  ScalarWalk(const double* q, const double* box) : q_(q), box_(box) {}
  // True when cell c's box holds the ball of squared radius `best` around q strictly: per axis the gap from q to
  // each face is > 0 and its square (rounded) is > best. The smallest gap decides: for g > 0 rounding is
  // monotonic, so fl(min g ^ 2) = min fl(g ^ 2).
  bool holds(const Cell& c, double best) const {
    double gap = std::numeric_limits<double>::infinity();
    for (int d = 0; d < 3; ++d)
      gap = std::min(gap, std::min(q_[d] - static_cast<double>(c.lo[d]), static_cast<double>(c.hi[d]) - q_[d]));
    return gap > 0.0 && gap * gap > best;
  }
  // Per axis the squared offset of q from cell c's box clipped to the tree's box (off[0..2]), and their sum in
  // the order x, y, z (a point's dist2 is summed alike, so the bound never exceeds a computed point distance).
  double bound(const Cell& c, double* off) const {
    for (int d = 0; d < 3; ++d) {
      const double below = static_cast<double>(c.lo[d]) - q_[d], above = q_[d] - static_cast<double>(c.hi[d]);
      const double g = std::max(std::max(below, above), 0.0);
      off[d] = std::max(g * g, box_[d]);
    }
    return off[0] + off[1] + off[2];
  }

 private:
  const double* q_;
  const double* box_;
};

// The leaf the descent reaches first: at each inner node the near child (the descent's choice, q on the near
// side of the cut's gap), without a stack. A tree with nodes.
inline std::uint32_t near_leaf(const Tree& t, const double* q) {
  const Node* nodes = t.nodes.data();
  std::uint32_t n = 0;
  while (!nodes[n].leaf()) {
    const Node& nd = nodes[n];
    const std::uint32_t d = nd.b & 3u;
    const bool left_near = q[d] - static_cast<double>(nd.lo) < static_cast<double>(nd.hi) - q[d];
    n = left_near ? n + 1 : nd.a;
  }
  return n;
}

// The exact nearest search that starts from a leaf (a tree with cells or fans): `leaf`, or when it is not a leaf's
// node index (a cold search: unset, stale from another tree) the near-path leaf of q (near_leaf), is scanned first,
// then the walk goes up through its ancestors: at each, the other child's subtree is searched (the descent)
// when its cell, clipped to the tree's box, is within the best distance (inclusive), and the walk stops at the
// first node N whose box holds the ball strictly (Walk: ScalarWalk or the AVX2 one).
// Exactness, ties included, from ANY start leaf (so the near-path start of a cold search is as exact as a warm
// one; it only skips the root descent's stack, and its first scan usually bounds the ball well): every point
// outside the leaf lies in the other child of exactly one node on the walk's path, and that subtree is either
// searched (the descent feeds the set every point whose dist2 is <= the best, which only shrinks) or skipped
// because its lower bound exceeds the best then (hence also every later best); the points outside N lie beyond
// one of N's faces f on some axis (each face is the near-side cut of an ancestor, and without kNoStop that cut
// is at or below / above the far side's), so for such a point P, |q - P| >= |f - q| per axis; rounding is
// monotonic, so its computed dist2 >= fl(g * g) for the smallest face gap g, and g * g > best means P cannot
// beat or tie the winner. NearestSet keeps the (dist2, slot)-smallest of what it is fed, whatever the order, so
// the answer is the root descent's bit for bit. `leaf` gets the winner's leaf (unchanged when there is none).
template <class Scan, class Walk>
void nearest_from(const Tree& t, const double* q, NearestSet& set, std::uint32_t& leaf) {
  using D = Descent<Scan, NearestSet>;
  D descent(t, q, set, 1.0);
  if (t.cells.empty() && t.fans.empty()) {
    descent.run();
    if (descent.won() != NearestSet::kNone) leaf = descent.won();
    return;
  }
  double box[3];
  D::box_offsets(t, q, box);
  const Walk walk(q, box);
  std::uint32_t n = leaf < t.nodes.size() && t.nodes[leaf].leaf() ? leaf : near_leaf(t, q);
  std::uint32_t won = NearestSet::kNone;
  const Node& start = t.nodes[n];
  if (start.a != start.b) {
    Scan::nearest(t, q, start.a, start.b, set);
    won = n;
  }
  if constexpr (Walk::kFans) {
    if (!t.fans.empty()) {
      // By fans: at each, every frontier node but the one the walk comes from is searched (nearest first) when its
      // cell is within the best distance, then the walk goes on at the fan's root R, stopping there when R's stop box
      // holds the ball. The frontier holds all of R's points, so the argument above holds with a fan for a level; the
      // stop box's faces are at the far side of each ancestor's cut (kdtree_build.cpp's stop_cells), which every point
      // outside R lies beyond, so it may be wider than R's cell and needs no kNoStop. Where the stop box does not hold
      // the ball but R's halo box does, the halo's nodes hold every point outside R that the ball may (Halo): once they
      // are searched, the walk stops there too.
      // Searches the nodes whose bits are set in `todo` (node(k); cell bound[k], per axis off[axis][k]) nearest first,
      // each while its bound is still within the best.
      auto nearest_first = [&](std::uint64_t todo, const double* bound, const auto* off, auto node) {
        while (todo != 0) {
          unsigned k = static_cast<unsigned>(__builtin_ctzll(todo));
          for (std::uint64_t rest = todo & (todo - 1); rest != 0; rest &= rest - 1) {
            const unsigned l = static_cast<unsigned>(__builtin_ctzll(rest));
            k = bound[l] < bound[k] ? l : k;
          }
          todo &= ~(std::uint64_t{1} << k);
          if (!(bound[k] <= set.best)) continue;  // the best shrank since
          const double o[3] = {off[0][k], off[1][k], off[2][k]};
          descent.run_from(node(k), o);
          if (descent.won() != NearestSet::kNone) won = descent.won();
        }
      };
      // Searches the frontier of the fan of lane `at` but that lane (where the walk comes from); true when the fan's
      // stop box then holds the ball.
      auto search_fan = [&](std::uint32_t at) {
        const Fan& fan = t.fans[at / kFanLanes];
        alignas(32) double bound[kFanLanes], off[3][kFanLanes];
        const unsigned todo =
            walk.fan_bounds(fan, t.fan_blocks.data() + fan.first, set.best, bound, off) & ~(1u << (at % kFanLanes));
        nearest_first(todo, bound, off, [&](unsigned k) { return t.lane_block(fan, k).node[k % kFanBlock]; });
        return walk.holds(fan.cell, set.best);
      };
      // The start leaf's fan first, then its halo when its stop box does not hold the ball but its halo box does
      // (only there: the halos of the fans above would cost more than the walk they save, RESULTS §76), else up.
      std::uint32_t at = t.fan_of[n];
      if (at != Tree::kNoFan && !search_fan(at)) {
        const Halo* h = t.halos.empty() ? nullptr : &t.halos[at / kFanLanes];
        if (h && h->count != 0 && walk.holds(h->reach, set.best)) {
          alignas(64) double hbound[kMaxHalo], hoff[3][kMaxHalo];
          const HaloBlock* blocks = t.halo_blocks.data() + h->first;
          nearest_first(walk.halo_bounds(*h, blocks, set.best, hbound, hoff), hbound, hoff,
                        [&](unsigned k) { return blocks[k / kHaloBlock].node[k % kHaloBlock]; });
        } else {
          for (at = t.fans[at / kFanLanes].up; at != Tree::kNoFan && !search_fan(at); at = t.fans[at / kFanLanes].up) {
          }
        }
      }
      if (set.slot != NearestSet::kNone) leaf = won;
      return;
    }
  }
  const Cell* cells = t.cells.data();
  while (n != 0) {
    const Cell& c = cells[n];
    if (!(c.parent & Cell::kNoStop) && walk.holds(c, set.best)) break;
    const std::uint32_t p = c.parent & ~Cell::kNoStop;
    const std::uint32_t s = n == p + 1 ? t.nodes[p].a : p + 1;
    alignas(32) double off[4];
    if (walk.bound(cells[s], off) <= set.best) {
      descent.run_from(s, off);
      if (descent.won() != NearestSet::kNone) won = descent.won();
    }
    n = p;
  }
  if (set.slot != NearestSet::kNone) leaf = won;
}

// One search entry per set type, for one leaf scan; a tree's owner picks the table once (kdtree.cpp).
struct SearchFns {
  void (*nearest)(const Tree&, const double* q, NearestSet&, double eps_factor);
  void (*knn)(const Tree&, const double* q, KnnSet&, double eps_factor);
  void (*radius)(const Tree&, const double* q, RadiusSet&, double eps_factor);
  void (*count)(const Tree&, const double* q, CountSet&, double eps_factor);
  void (*nearest_from)(const Tree&, const double* q, NearestSet&, std::uint32_t& leaf);  // exact only
  bool fans;  // nearest_from walks by fans when the tree has them (build_fans)
};

template <class Scan, class Set>
void search_with(const Tree& t, const double* q, Set& set, double eps_factor) {
  Descent<Scan, Set>(t, q, set, eps_factor).run();
}

template <class Scan, class Walk>
constexpr SearchFns search_fns() {
  return {&search_with<Scan, NearestSet>, &search_with<Scan, KnnSet>, &search_with<Scan, RadiusSet>,
          &search_with<Scan, CountSet>, &nearest_from<Scan, Walk>, Walk::kFans};
}

// The AVX2 leaf scans' and walk's table (kdtree_avx2.cpp); nullptr when that file was built without AVX2 (then
// never chosen). avx512_search(): the same file built for AVX-512VL (kdtree_avx512.cpp); nullptr when built without.
// The caller checks the CPU (__builtin_cpu_supports).
const SearchFns* avx2_search();
const SearchFns* avx512_search();

}  // namespace surfeledit::kd
