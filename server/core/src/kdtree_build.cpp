// Build of the k-d tree's flat layout (kdtree_search.hpp; docs/algorithms.md §3).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <utility>

#include "kdtree_search.hpp"

namespace surfeledit::kd {

namespace {

struct Box {
  double lo[3], hi[3];
  static Box empty() {
    constexpr double inf = std::numeric_limits<double>::infinity();
    return {{inf, inf, inf}, {-inf, -inf, -inf}};
  }
  void add(const double* p) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  }
  void add(const Box& o) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], o.lo[d]);
      hi[d] = std::max(hi[d], o.hi[d]);
    }
  }
  int widest() const {
    int dim = 0;
    for (int d = 1; d < 3; ++d)
      if (hi[d] - lo[d] > hi[dim] - lo[dim]) dim = d;
    return dim;
  }
};

// The bounding box of slots [b, e) of `t` (its coordinate arrays).
Box box_of(const Tree& t, std::uint32_t b, std::uint32_t e) {
  Box box = Box::empty();
  for (std::uint32_t i = b; i < e; ++i) {
    const double p[3] = {t.xs()[i], t.ys()[i], t.zs()[i]};
    box.add(p);
  }
  return box;
}

constexpr int kBits = 10;                                  // Morton code bits per axis (30-bit codes)
constexpr double kCells = static_cast<double>((1 << kBits) - 1);  // largest cell coordinate
constexpr int kDigit = 10, kPasses = 3 * kBits / kDigit;          // radix sort: 3 passes of 10 bits

// Builds over points sorted along a Morton curve: a range of equal code prefix is one cell; it splits
// at its highest differing code bit (the cell's midpoint on that bit's axis), found by binary search.
// Ranges of equal codes (points within one cell of 2^-16 of the box) split at their median on the widest axis.
class MortonBuilder {
 public:
  MortonBuilder(Tree& t, std::vector<std::uint32_t>& code, std::uint32_t leaf) : t_(t), code_(code), leaf_(leaf) {}

  Box build(std::uint32_t b, std::uint32_t e) {
    const std::uint32_t ni = static_cast<std::uint32_t>(t_.nodes.size());
    t_.nodes.emplace_back();
    const std::uint32_t diff = code_[b] ^ code_[e - 1];
    std::uint32_t m;
    int dim;
    if (e - b <= leaf_) return leaf(ni, b, e);
    if (diff != 0) {
      const int bit = 31 - __builtin_clz(diff);
      dim = bit % 3;
      m = static_cast<std::uint32_t>(
          std::partition_point(code_.begin() + b, code_.begin() + e,
                               [bit](std::uint32_t c) { return ((c >> bit) & 1u) == 0; }) -
          code_.begin());
    } else {
      const Box box = box_of(t_, b, e);
      dim = box.widest();
      if (!(box.hi[dim] > box.lo[dim])) return leaf(ni, b, e);  // all points equal
      m = b + (e - b) / 2;
      median_split(b, e, m, dim);
    }
    const Box left = build(b, m);
    t_.nodes[ni].a = static_cast<std::uint32_t>(t_.nodes.size());
    Box right = build(m, e);
    Node& nd = t_.nodes[ni];
    nd.b = kInner | static_cast<std::uint32_t>(dim);
    nd.lo = round_up(left.hi[dim]);
    nd.hi = round_down(right.lo[dim]);
    right.add(left);
    return right;
  }

 private:
  Box leaf(std::uint32_t ni, std::uint32_t b, std::uint32_t e) {
    t_.nodes[ni].a = b;
    t_.nodes[ni].b = e;
    return box_of(t_, b, e);
  }

  // Reorders slots [b, e) so those before m are <= those after along `dim` (all codes in the range are equal).
  void median_split(std::uint32_t b, std::uint32_t e, std::uint32_t m, int dim) {
    std::vector<std::uint32_t> perm(e - b);
    std::iota(perm.begin(), perm.end(), b);
    const double* axis = t_.coords.data() + static_cast<std::size_t>(dim) * t_.stride;
    std::nth_element(perm.begin(), perm.begin() + (m - b), perm.end(),
                     [&](std::uint32_t x, std::uint32_t y) { return axis[x] < axis[y]; });
    std::vector<double> p(perm.size());
    for (int d = 0; d < 3; ++d) {
      double* c = t_.coords.data() + static_cast<std::size_t>(d) * t_.stride;
      for (std::size_t i = 0; i < perm.size(); ++i) p[i] = c[perm[i]];
      std::copy(p.begin(), p.end(), c + b);
    }
    std::vector<std::uint32_t> r(perm.size());
    for (std::size_t i = 0; i < perm.size(); ++i) r[i] = t_.rows[perm[i]];
    std::copy(r.begin(), r.end(), t_.rows.begin() + b);
  }

  Tree& t_;
  std::vector<std::uint32_t>& code_;
  std::uint32_t leaf_;
};

}  // namespace

// LSD radix sort of (key, value) pairs on the low 3 * kBits key bits; all digit histograms are counted in
// one read, and a pass whose digit is the same for every key is skipped. Each pair travels as one 64-bit word
// (key high, value low), so a pass scatters one stream per bucket instead of two.
void radix_sort(std::vector<std::uint32_t>& key, std::vector<std::uint32_t>& val) {
  const std::size_t n = key.size();
  constexpr std::uint32_t kBuckets = 1u << kDigit, kMask = kBuckets - 1;
  std::vector<std::uint32_t> count(kPasses * kBuckets, 0u);
  for (std::size_t i = 0; i < n; ++i)
    for (int p = 0; p < kPasses; ++p) ++count[p * kBuckets + ((key[i] >> (p * kDigit)) & kMask)];
  // A pass whose digit is the same for every key would leave the order as it is: only the others run.
  std::vector<int> passes;
  for (int p = 0; p < kPasses; ++p) {
    const std::uint32_t* c = &count[p * kBuckets];
    if (*std::max_element(c, c + kBuckets) != n) passes.push_back(p);
  }
  if (passes.empty()) return;
  std::unique_ptr<std::uint64_t[]> a(new std::uint64_t[n]), b(new std::uint64_t[n]);  // not zero-filled
  for (std::size_t i = 0; i < n; ++i) a[i] = (static_cast<std::uint64_t>(key[i]) << 32) | val[i];
  for (const int p : passes) {
    std::uint32_t* c = &count[p * kBuckets];
    std::uint32_t sum = 0;
    for (std::uint32_t k = 0; k < kBuckets; ++k) {
      const std::uint32_t here = c[k];
      c[k] = sum;
      sum += here;
    }
    const int shift = 32 + p * kDigit;
    for (std::size_t i = 0; i < n; ++i) b[c[(a[i] >> shift) & kMask]++] = a[i];
    a.swap(b);
  }
  for (std::size_t i = 0; i < n; ++i) {
    key[i] = static_cast<std::uint32_t>(a[i] >> 32);
    val[i] = static_cast<std::uint32_t>(a[i]);
  }
}

void build(Tree& t, const double* points, std::vector<std::uint32_t> rows, const double* origin, const double* lo,
           const double* hi, std::uint32_t leaf) {
  const std::size_t n = rows.size();
  t = Tree();
  if (n == 0) return;
  std::copy_n(lo, 3, t.box_lo);
  std::copy_n(hi, 3, t.box_hi);
  // Cubic cells over the box (one scale for all axes, so a cut halves a cell's longest side), kBits per axis.
  double ext = 0.0;
  for (int d = 0; d < 3; ++d) ext = std::max(ext, hi[d] - lo[d]);
  const double scale = ext > 0.0 ? kCells / ext : 0.0;
  std::vector<std::uint32_t> code(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double* p = points + 3 * static_cast<std::size_t>(rows[i]);
    std::uint32_t c = 0;
    for (int d = 0; d < 3; ++d) {
      const double x = std::min(kCells, std::max(0.0, (p[d] - origin[d] - lo[d]) * scale));
      c |= spread10(static_cast<std::uint32_t>(x)) << d;
    }
    code[i] = c;
  }
  radix_sort(code, rows);
  t.rows = std::move(rows);
  // One array per coordinate in slot order, each followed by its zero tail.
  t.stride = n + Tree::kTail;
  t.coords.resize(3 * t.stride);
  double* c = t.coords.data();
  for (std::size_t i = 0; i < n; ++i) {
    const double* p = points + 3 * static_cast<std::size_t>(t.rows[i]);
    c[i] = p[0] - origin[0];
    c[t.stride + i] = p[1] - origin[1];
    c[2 * t.stride + i] = p[2] - origin[2];
  }
  for (int d = 0; d < 3; ++d) std::fill_n(c + d * t.stride + n, Tree::kTail, 0.0);
  t.nodes.reserve(n / std::max<std::uint32_t>(1, leaf / 2) + 16);
  MortonBuilder(t, code, leaf).build(0, static_cast<std::uint32_t>(n));
  t.nodes.shrink_to_fit();
}

// Pre-order: a node's parent comes before it, so one pass hands each inner node's box, narrowed by its cut, to
// its children (left: the cut's lo as its upper face, right: its hi as its lower face); a leaf then clips its own.
void build_cells(Tree& t) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  t.cells.assign(t.nodes.size(), Cell{{-inf, -inf, -inf}, {inf, inf, inf}, 0});
  for (std::uint32_t i = 0; i < t.nodes.size(); ++i) {
    const Node& nd = t.nodes[i];
    if (nd.leaf()) {  // clipped to its points' box, rounded outward (empty: lo = +inf, hi = -inf, never searched)
      Cell& c = t.cells[i];
      const Box box = box_of(t, nd.a, nd.b);
      for (int d = 0; d < 3; ++d) {
        c.lo[d] = std::max(c.lo[d], round_down(box.lo[d]));
        c.hi[d] = std::min(c.hi[d], round_up(box.hi[d]));
      }
      c.parent |= Cell::kNoStop;
      continue;
    }
    const Cell& c = t.cells[i];
    const std::uint32_t d = nd.b & 3u;
    const std::uint32_t overlap = (c.parent & Cell::kNoStop) | (nd.lo > nd.hi ? Cell::kNoStop : 0u);
    Cell left = c, right = c;
    left.hi[d] = std::min(c.hi[d], nd.lo);
    right.lo[d] = std::max(c.lo[d], nd.hi);
    left.parent = right.parent = i | overlap;
    t.cells[i + 1] = left;
    t.cells[nd.a] = right;
  }
}

// Per node its stop box for the walk (Fan::cell): each ancestor's cut bounds it at the FAR child's extent (a left
// child's upper face is the cut's hi, <= every coordinate of the right child; a right child's lower face the cut's
// lo), so every point outside the node lies beyond one of its faces, whatever the children's extents (no kNoStop).
// Wider than the node's cell by each cut's gap: a query just outside a surface's points (above a plate's top
// face, between two rows of samples) is held one level sooner. Pre-order, as build_cells.
static std::vector<Cell> stop_cells(const Tree& t) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  std::vector<Cell> stop(t.nodes.size(), Cell{{-inf, -inf, -inf}, {inf, inf, inf}, 0});
  for (std::uint32_t i = 0; i < t.nodes.size(); ++i) {
    const Node& nd = t.nodes[i];
    if (nd.leaf()) continue;
    const std::uint32_t d = nd.b & 3u;
    Cell left = stop[i], right = stop[i];
    left.hi[d] = std::min(left.hi[d], nd.hi);
    right.lo[d] = std::max(right.lo[d], nd.lo);
    stop[i + 1] = left;
    stop[nd.a] = right;
  }
  return stop;
}

// Pre-order: a node's depth is its parent's plus one. Each fan's frontier is collected depth first, left child
// first, so its lanes are in pre-order.
void build_fans(Tree& t) {
  const std::size_t n = t.nodes.size();
  t.fans.clear();
  t.fan_blocks.clear();
  t.fan_of.clear();
  t.halos.clear();
  t.halo_blocks.clear();
  if (t.cells.size() != n || n < 2) return;
  t.fan_of.assign(n, Tree::kNoFan);
  std::vector<std::uint8_t> level(n, 0);  // depth modulo kFanLevels
  for (std::uint32_t i = 0; i < n; ++i) {
    const Node& nd = t.nodes[i];
    if (nd.leaf()) continue;
    level[i + 1] = level[nd.a] = static_cast<std::uint8_t>((level[i] + 1) % kFanLevels);
  }
  constexpr float inf = std::numeric_limits<float>::infinity();
  const std::vector<Cell> stop = stop_cells(t);
  std::vector<std::pair<std::uint32_t, int>> stack;  // (node, levels below the fan's root)
  std::vector<std::uint32_t> frontier;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (t.nodes[i].leaf() || level[i] != 0) continue;
    frontier.clear();
    stack.assign({{t.nodes[i].a, 1}, {i + 1, 1}});  // popped left first
    while (!stack.empty()) {
      const auto [m, below] = stack.back();
      stack.pop_back();
      const Node& nd = t.nodes[m];
      if (nd.leaf() || below == kFanLevels) {
        frontier.push_back(m);
      } else {
        stack.push_back({nd.a, below + 1});
        stack.push_back({m + 1, below + 1});
      }
    }
    Fan f;
    f.cell = stop[i];
    f.up = i;  // R until every fan is made (below)
    f.first = static_cast<std::uint32_t>(t.fan_blocks.size());
    const std::uint32_t fan = static_cast<std::uint32_t>(t.fans.size());
    for (std::size_t k = 0; k < frontier.size(); k += kFanBlock) {
      FanBlock b;
      for (int d = 0; d < 3; ++d) {
        std::fill_n(b.lo[d], kFanBlock, inf);
        std::fill_n(b.hi[d], kFanBlock, -inf);
      }
      std::fill_n(b.node, kFanBlock, 0u);
      for (std::size_t j = k; j < std::min(frontier.size(), k + kFanBlock); ++j) {
        const std::uint32_t m = frontier[j];
        const Cell& c = t.cells[m];
        for (int d = 0; d < 3; ++d) {
          b.lo[d][j - k] = c.lo[d];
          b.hi[d][j - k] = c.hi[d];
        }
        b.node[j - k] = m;
        f.lanes |= 1u << j;
        t.fan_of[m] = fan * kFanLanes + static_cast<std::uint32_t>(j);
      }
      t.fan_blocks.push_back(b);
    }
    t.fans.push_back(f);
  }
  std::vector<std::uint32_t> roots(t.fans.size());
  for (std::size_t k = 0; k < roots.size(); ++k) roots[k] = t.fans[k].up;
  build_halos(t, roots);
  for (Fan& f : t.fans) f.up = t.fan_of[f.up];  // each R's lane was set by its parent fan, made before it (pre-order)
  t.fans.shrink_to_fit();
  t.fan_blocks.shrink_to_fit();
  std::vector<Cell>().swap(t.cells);
}

}  // namespace surfeledit::kd
