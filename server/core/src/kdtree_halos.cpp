// The k-d tree's fan halos (kdtree_search.hpp's Halo): per fan, the nodes outside its root that reach into a box
// around the root's points, so that the search from a leaf can stop going up once its ball lies in that box
// (kdtree_walk.hpp; docs/algorithms.md §3, RESULTS §76).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "kdtree_search.hpp"

namespace surfeledit::kd {

namespace {

struct FloatBox {
  float lo[3], hi[3];
  bool empty() const { return !(lo[0] <= hi[0]); }
  float longest() const { return std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}); }
  bool meets(const FloatBox& o) const {
    for (int d = 0; d < 3; ++d)
      if (lo[d] > o.hi[d] || o.lo[d] > hi[d]) return false;
    return true;
  }
};

// A node's box clipped to the reach box, as codes: per axis the largest code whose value (Halo::value) is at or
// below the clipped lower face and the smallest at or above the clipped upper face. False when a face is beyond
// the codes' range (rounding on a box too small for its offset): the fan then gets no halo.
bool encode(const FloatBox& b, const Cell& reach, HaloBlock& block, int lane) {
  for (int d = 0; d < 3; ++d) {
    const double lo = std::max(static_cast<double>(b.lo[d]), static_cast<double>(reach.lo[d]));
    const double hi = std::min(static_cast<double>(b.hi[d]), static_cast<double>(reach.hi[d]));
    const double step = Halo::step(reach, d);
    const double per = step > 0.0 ? 1.0 / step : 0.0;
    // A first guess from the offsets (truncated: they are >= 0 up to rounding), then the exact codes by their values.
    auto guess = [&](double x) {
      return static_cast<int>(std::min(255.0, std::max(0.0, (x - static_cast<double>(reach.lo[d])) * per)));
    };
    int ql = guess(lo), qh = guess(hi);
    while (ql > 0 && Halo::value(reach, d, ql) > lo) --ql;
    while (ql < 255 && Halo::value(reach, d, ql + 1) <= lo) ++ql;
    while (qh < 255 && Halo::value(reach, d, qh) < hi) ++qh;
    while (qh > 0 && Halo::value(reach, d, qh - 1) >= hi) --qh;
    if (Halo::value(reach, d, ql) > lo || Halo::value(reach, d, qh) < hi) return false;
    block.lo[d][lane] = static_cast<std::uint8_t>(ql);
    block.hi[d][lane] = static_cast<std::uint8_t>(qh);
  }
  return true;
}

}  // namespace

void build_halos(Tree& t, const std::vector<std::uint32_t>& roots) {
  const std::size_t n = t.nodes.size();
  t.halos.assign(roots.size(), Halo{});
  t.halo_blocks.clear();
  // Per node the box of its points (a leaf's cell is its points' box, rounded outward) and one past its subtree.
  constexpr float inf = std::numeric_limits<float>::infinity();
  std::vector<FloatBox> box(n);
  std::vector<std::uint32_t> end(n);
  for (std::size_t k = n; k-- > 0;) {
    const Node& nd = t.nodes[k];
    FloatBox& b = box[k];
    if (nd.leaf()) {
      end[k] = static_cast<std::uint32_t>(k + 1);
      for (int d = 0; d < 3; ++d) {
        b.lo[d] = nd.a == nd.b ? inf : t.cells[k].lo[d];
        b.hi[d] = nd.a == nd.b ? -inf : t.cells[k].hi[d];
      }
      continue;
    }
    end[k] = end[nd.a];
    for (int d = 0; d < 3; ++d) {
      b.lo[d] = std::min(box[k + 1].lo[d], box[nd.a].lo[d]);
      b.hi[d] = std::max(box[k + 1].hi[d], box[nd.a].hi[d]);
    }
  }
  std::vector<std::uint32_t> found, stack;
  for (std::size_t f = 0; f < roots.size(); ++f) {
    // Only where a search starts: a fan with a leaf among its frontier (the walk reads no other fan's halo).
    const Fan& fan = t.fans[f];
    bool leaves = false;
    for (unsigned lanes = fan.lanes; lanes != 0; lanes &= lanes - 1) {
      const unsigned k = static_cast<unsigned>(__builtin_ctz(lanes));
      leaves |= t.nodes[t.lane_block(fan, k).node[k % kFanBlock]].leaf();
    }
    const std::uint32_t r = roots[f];
    const FloatBox& T = box[r];
    if (!leaves || T.empty()) continue;
    const double side = T.longest();
    const double margin = kHaloReach * side;
    Halo h{};  // reach.parent 0
    FloatBox E;
    bool finite = true;  // a box beyond float range (or its codes' step) would make no bound: no halo then
    for (int d = 0; d < 3; ++d) {
      E.lo[d] = h.reach.lo[d] = round_down(static_cast<double>(T.lo[d]) - margin);
      E.hi[d] = h.reach.hi[d] = round_up(static_cast<double>(T.hi[d]) + margin);
      finite &= std::isfinite(E.lo[d]) && std::isfinite(E.hi[d]) && std::isfinite(Halo::step(h.reach, d));
    }
    if (!finite) continue;
    // The nodes outside R whose points' box meets E: leaves, or nodes no longer than kHaloCoarse of T, found from the
    // root down through R's ancestors (the rest pruned by their boxes).
    found.clear();
    stack.assign({0u});
    bool over = false;
    while (!stack.empty() && !over) {
      const std::uint32_t m = stack.back();
      stack.pop_back();
      if (m == r) continue;
      const bool above_r = m < r && r < end[m];
      if (!above_r && (box[m].empty() || !box[m].meets(E))) continue;
      const Node& nd = t.nodes[m];
      if (!above_r && (nd.leaf() || box[m].longest() <= kHaloCoarse * side)) {
        found.push_back(m);
        over = found.size() > static_cast<std::size_t>(kMaxHalo);
      } else {
        stack.push_back(nd.a);
        stack.push_back(m + 1);
      }
    }
    if (over || found.empty()) continue;
    h.first = static_cast<std::uint32_t>(t.halo_blocks.size());
    h.count = static_cast<std::uint32_t>(found.size());
    bool coded = true;
    for (std::size_t k = 0; k < found.size() && coded; k += kHaloBlock) {
      HaloBlock b{};
      for (std::size_t j = k; j < std::min(found.size(), k + kHaloBlock) && coded; ++j) {
        coded = encode(box[found[j]], h.reach, b, static_cast<int>(j - k));
        b.node[j - k] = found[j];
      }
      t.halo_blocks.push_back(b);
    }
    if (!coded) {
      t.halo_blocks.resize(h.first);
      continue;
    }
    t.halos[f] = h;
  }
  t.halo_blocks.shrink_to_fit();
}

}  // namespace surfeledit::kd
