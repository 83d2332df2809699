// Member definitions of Bvh<Box> (bvh.hpp). Included by src/bvh/bvh.cpp, which instantiates them
// for Aabb, Obb and Sphere; include it elsewhere only to instantiate a new box kind.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "surfeledit/core/bvh/bvh.hpp"

namespace surfeledit::bvh {

template <class Box>
void Bvh<Box>::reset_steps(const BvhParams& params) {
  stop_journal();
  params_ = params;
  live_ = static_cast<Index>(order_.size());
  extras_ = 0;
  dead_ = 0;
  extra_next_.clear();
  extra_row_.clear();
  refit_since_build_ = false;
  step_ = 0;
  height_ = 0;
  cut_ = 0;
  positions_ = nullptr;
  radii_ = nullptr;
  previous_ = nullptr;
  shift_ = 0.0;
  reach_ = 0.0;
  refit_all_ = false;
}

template <class Box>
void Bvh<Box>::index_nodes() {
  Index max_row = -1;
  for (Index r : order_) max_row = std::max(max_row, r);
  leaf_of_row_.assign(static_cast<std::size_t>(max_row + 1), -1);
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    if (nodes_[k].leaf())
      for (std::int32_t s = nodes_[k].begin; s < nodes_[k].end; ++s) leaf_of_row_[order_[s]] = static_cast<std::int32_t>(k);
  extra_head_.assign(nodes_.size(), -1);
  stamp_.assign(nodes_.size(), 0);
  masks_.assign(nodes_.size(), 0);
  marks_.assign(nodes_.size(), 0);
  mark_ = 1;
  since_.assign(nodes_.size(), shift_);
}

template <class Box>
void Bvh<Box>::build(const Points& positions, const Values& radii, const IndexList& rows, const BvhParams& params) {
  validate(params);
  const auto t0 = std::chrono::steady_clock::now();
  nodes_.clear();
  order_ = rows;
  reset_steps(params);
  const std::int32_t n = static_cast<std::int32_t>(order_.size());
  if (n > 0) {
    nodes_.reserve(static_cast<std::size_t>(2 * (n / std::max(1, params.leaf_min_surfels)) + 1));
    Node root;
    root.begin = 0;
    root.end = n;
    nodes_.push_back(root);
    std::vector<std::int32_t> stack{0};
    std::vector<double> proj;
    while (!stack.empty()) {
      const std::int32_t i = stack.back();
      stack.pop_back();
      const std::int32_t begin = nodes_[i].begin, end = nodes_[i].end, level = nodes_[i].level;
      const std::int32_t count = end - begin;
      Index* rows_ptr = order_.data() + begin;
      nodes_[i].box = Box::fit(positions, radii, rows_ptr, static_cast<std::size_t>(count));
      height_ = std::max(height_, level + 1);
      if (level >= params.max_level || count <= params.leaf_max_surfels || count < 2 * params.leaf_min_surfels) continue;
      const Vec3 dir = Box::split_direction(nodes_[i].box, positions, rows_ptr, static_cast<std::size_t>(count));
      double mean = 0.0;
      for (std::int32_t k = 0; k < count; ++k) mean += positions.row(rows_ptr[k]).dot(dir);
      mean /= count;
      Index* mid = std::partition(rows_ptr, rows_ptr + count,
                                  [&](Index r) { return positions.row(r).dot(dir) < mean; });
      std::int32_t cut = static_cast<std::int32_t>(mid - rows_ptr);
      const std::int32_t lo_cut = params.leaf_min_surfels, hi_cut = count - params.leaf_min_surfels;
      if (cut < lo_cut || cut > hi_cut) {
        // The mean leaves a side too small (or empty): take the nearest admissible cut by rank.
        cut = std::clamp(cut, lo_cut, hi_cut);
        std::nth_element(rows_ptr, rows_ptr + cut, rows_ptr + count, [&](Index a, Index b) {
          return positions.row(a).dot(dir) < positions.row(b).dot(dir);
        });
      }
      const std::int32_t c = static_cast<std::int32_t>(nodes_.size());
      Node left, right;
      left.parent = right.parent = i;
      left.level = right.level = level + 1;
      left.begin = begin;
      left.end = right.begin = begin + cut;
      right.end = end;
      nodes_[i].first_child = c;
      nodes_.push_back(left);
      nodes_.push_back(right);
      stack.push_back(c + 1);
      stack.push_back(c);
    }
    // thesis §10.1.1: minimum leaf extent, then every parent at least as large as (containing) its children.
    for (std::size_t k = nodes_.size(); k-- > 0;) {
      Node& nd = nodes_[k];
      if (nd.leaf()) {
        if (params.min_leaf_extent > 0.0) nd.box.enforce_min_extent(params.min_leaf_extent);
      } else {
        nd.box.grow_over_child(nodes_[nd.first_child].box);
        nd.box.grow_over_child(nodes_[nd.first_child + 1].box);
      }
    }
  }
  index_nodes();
  build_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

template <class Box>
void Bvh<Box>::adopt(std::vector<Node> nodes, IndexList order, const BvhParams& params) {
  validate(params);
  const auto t0 = std::chrono::steady_clock::now();
  const std::int32_t n_nodes = static_cast<std::int32_t>(nodes.size());
  const std::int32_t n_rows = static_cast<std::int32_t>(order.size());
  auto broken = [](std::int32_t k, const char* what) {
    throw Error(ErrorCode::Internal, "node " + std::to_string(k), std::string("adopted tree: ") + what);
  };
  if (n_nodes > 0 && (nodes[0].parent != -1 || nodes[0].begin != 0 || nodes[0].end != n_rows)) broken(0, "bad root");
  int height = 0;
  for (std::int32_t k = 0; k < n_nodes; ++k) {
    const Node& nd = nodes[static_cast<std::size_t>(k)];
    if (nd.begin < 0 || nd.end < nd.begin || nd.end > n_rows) broken(k, "slot range out of bounds");
    height = std::max(height, nd.level + 1);
    if (nd.leaf()) continue;
    const std::int32_t c = nd.first_child;
    if (c <= k || c + 1 >= n_nodes) broken(k, "children must follow their parent");
    const Node& l = nodes[static_cast<std::size_t>(c)];
    const Node& r = nodes[static_cast<std::size_t>(c + 1)];
    if (l.parent != k || r.parent != k || l.begin != nd.begin || l.end != r.begin || r.end != nd.end ||
        l.level != nd.level + 1 || r.level != nd.level + 1)
      broken(k, "children do not split the parent's range");
  }
  for (Index r : order)
    if (r < 0) throw Error(ErrorCode::Internal, "order", "adopted tree: negative row");
  nodes_ = std::move(nodes);
  order_ = std::move(order);
  reset_steps(params);
  height_ = height;
  index_nodes();
  build_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

template <class Box>
std::size_t Bvh<Box>::memory_bytes() const {
  return nodes_.capacity() * sizeof(Node) + order_.capacity() * sizeof(Index) +
         leaf_of_row_.capacity() * sizeof(std::int32_t) +
         (extra_head_.capacity() + extra_next_.capacity()) * sizeof(std::int32_t) + extra_row_.capacity() * sizeof(Index) +
         stamp_.capacity() * sizeof(std::uint64_t) + masks_.capacity() + marks_.capacity() * sizeof(std::uint32_t) +
         since_.capacity() * sizeof(double);
}

template <class Box>
void Bvh<Box>::compact_leaf(std::int32_t leaf) {
  if (dead_ == 0) return;  // nothing removed since the last build
  Node& nd = mut(leaf);
  std::int32_t w = nd.begin;
  for (std::int32_t s = nd.begin; s < nd.end; ++s)
    if (order_[s] >= 0) order_[w++] = order_[s];
  for (std::int32_t s = w; s < nd.end; ++s) order_[s] = kDeadRow;
  nd.end = w;
  // Unlink dead inserted entries.
  std::int32_t* link = &extra_head_[leaf];
  while (*link >= 0) {
    if (extra_row_[*link] < 0) *link = extra_next_[*link];
    else link = &extra_next_[*link];
  }
}

template <class Box>
Aabb Bvh<Box>::tight_aabb(std::int32_t node) const {
  // Hot loop of every refit: raw row-major access, no temporaries.
  const double* p = positions_->data();
  const double* r = radii_->size() ? radii_->data() : nullptr;
  double lo0 = std::numeric_limits<double>::infinity(), lo1 = lo0, lo2 = lo0;
  double hi0 = -lo0, hi1 = -lo0, hi2 = -lo0;
  auto add = [&](Index row) {
    const double* q = p + 3 * static_cast<std::ptrdiff_t>(row);
    const double rad = r ? r[row] : 0.0;
    lo0 = std::min(lo0, q[0] - rad);
    lo1 = std::min(lo1, q[1] - rad);
    lo2 = std::min(lo2, q[2] - rad);
    hi0 = std::max(hi0, q[0] + rad);
    hi1 = std::max(hi1, q[1] + rad);
    hi2 = std::max(hi2, q[2] + rad);
  };
  // The node's own slots in a loop of its own, so the six bounds stay in registers (through for_each_row,
  // not inlined, every min / max went through memory: RESULTS §39). Inserted surfels hang off leaves:
  // for_each_row then adds them too (adding a slot's row twice changes no min / max).
  const Node& nd = nodes_[static_cast<std::size_t>(node)];
  for (std::int32_t s = nd.begin; s < nd.end; ++s)
    if (order_[s] >= 0) add(order_[s]);
  if (extras_ != 0) for_each_row(node, add);
  Aabb b;
  b.lo = Vec3(lo0, lo1, lo2);
  b.hi = Vec3(hi0, hi1, hi2);
  if (nodes_[node].leaf() && params_.min_leaf_extent > 0.0 && !b.empty()) b.enforce_min_extent(params_.min_leaf_extent);
  return b;
}

// Recomputes (from `tight`, plus inflation) each axis in `axes` along which `tight` leaves `box`;
// returns the bit mask (1 = x, 2 = y, 4 = z) of the axes changed.
template <class Box>
unsigned Bvh<Box>::refit_axes(Aabb& box, const Aabb& tight, unsigned axes) const {
  unsigned changed = 0;
  for (int d = 0; d < 3; ++d) {
    if (!(axes & (1u << d))) continue;
    if (tight.lo[d] < box.lo[d] || tight.hi[d] > box.hi[d]) {
      box.lo[d] = tight.lo[d] - params_.inflation;
      box.hi[d] = tight.hi[d] + params_.inflation;
      changed |= 1u << d;
    }
  }
  return changed;
}

template <class Box>
void Bvh<Box>::grow_ancestors(std::int32_t node) {
  std::int32_t child = node;
  std::int32_t p = nodes_[node].parent;
  while (p >= 0 && !nodes_[p].box.contains(nodes_[child].box)) {
    mut(p).box.enclose(nodes_[child].box);
    refit_since_build_ = true;
    child = p;
    p = nodes_[p].parent;
  }
}

template <class Box>
int Bvh<Box>::bottom_up_levels() const {
  switch (params_.update) {
    case UpdateMode::BottomUp:
    case UpdateMode::Bounded: return height_;  // refit() of a bounded tree: every node (step_bounded() is its step)
    case UpdateMode::TopDown: return 0;
    case UpdateMode::Hybrid: break;
  }
  return static_cast<int>(std::lround(params_.hybrid_f * height_));
}

template <class Box>
template <class B, class>
BvhCounters Bvh<Box>::refit(const Points& positions, const Values& radii) {
  if (journal_.on) throw Error(ErrorCode::Internal, "journal", "refit() of a journaled tree (only bounded steps are)");
  BvhCounters c;
  positions_ = &positions;
  radii_ = &radii;
  ++step_;
  cut_ = bottom_up_levels();
  bool changed_any = false;
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    const std::int32_t i = static_cast<std::int32_t>(k);
    Node& nd = nodes_[k];
    if (nd.level >= cut_) continue;  // refit lazily by touch()
    unsigned m = 0;
    if (nd.leaf() || nd.level == cut_ - 1) {
      // Deepest bottom-up node: fit from its surfels (leaves drop their dead slots first).
      if (nd.leaf()) compact_leaf(i);
      const Aabb tight = tight_aabb(i);
      ++c.nu;
      if (!tight.empty()) {
        m = refit_axes(nd.box, tight, 7u);
      } else if (!nd.box.empty()) {
        nd.box = Aabb{};  // no live surfel left: an empty box overlaps nothing and fits in any parent
        m = 7u;
      }
    } else {
      const unsigned child_mask = masks_[nd.first_child] | masks_[nd.first_child + 1];
      if (child_mask) {
        Aabb u = nodes_[nd.first_child].box;
        u.expand(nodes_[nd.first_child + 1].box);
        ++c.nu;
        m = refit_axes(nd.box, u, child_mask);
      }
    }
    masks_[k] = static_cast<std::uint8_t>(m);
    stamp_[k] = step_;
    changed_any |= m != 0;
  }
  if (changed_any) refit_since_build_ = true;
  return c;
}

template <class Box>
template <class B, class>
void Bvh<Box>::refit_touched(std::int32_t node, BvhCounters& counters) {
  if (positions_ == nullptr) return;  // never refit: the build is current
  Node& nd = nodes_[static_cast<std::size_t>(node)];
  if (nd.leaf()) compact_leaf(node);
  Aabb tight = tight_aabb(node);
  ++counters.nu;
  if (!tight.empty()) tight.inflate(params_.inflation);  // else: no live surfel, the box becomes empty
  if (tight.lo != nd.box.lo || tight.hi != nd.box.hi) {
    nd.box = tight;
    refit_since_build_ = true;
    grow_ancestors(node);
  }
}

template <class Box>
template <class B, class>
void Bvh<Box>::touch_all(BvhCounters& counters) {
  for (std::size_t k = 0; k < nodes_.size(); ++k) touch(static_cast<std::int32_t>(k), counters);
}

template <class Box>
void Bvh<Box>::on_removed(const std::vector<bool>& keep) {
  stop_journal();
  std::vector<Index> remap(keep.size(), kDeadRow);
  Index next = 0;
  for (std::size_t r = 0; r < keep.size(); ++r)
    if (keep[r]) remap[r] = next++;
  std::vector<std::int32_t> leaf_of(static_cast<std::size_t>(next), -1);
  for (std::size_t r = 0; r < keep.size() && r < leaf_of_row_.size(); ++r)
    if (keep[r]) leaf_of[static_cast<std::size_t>(remap[r])] = leaf_of_row_[r];
  leaf_of_row_.swap(leaf_of);
  bool removed = false;
  auto apply = [&](Index& row) {
    if (row < 0) return;
    const Index nr = static_cast<std::size_t>(row) < remap.size() ? remap[static_cast<std::size_t>(row)] : kDeadRow;
    if (nr < 0) {
      removed = true;
      --live_;
      ++dead_;
    }
    row = nr;
  };
  for (Index& row : order_) apply(row);
  for (Index& row : extra_row_) {
    const bool was = row >= 0;
    apply(row);
    if (was && row < 0) --extras_;
  }
  if (removed) refit_since_build_ = true;
}

template <class Box>
BvhCounters Bvh<Box>::on_inserted(const Points& positions, const Values& radii, const IndexList& parents) {
  stop_journal();
  BvhCounters c;
  const Index first = static_cast<Index>(positions.rows() - static_cast<Eigen::Index>(parents.size()));
  leaf_of_row_.resize(static_cast<std::size_t>(positions.rows()), -1);
  for (std::size_t k = 0; k < parents.size(); ++k) {
    const Index parent = parents[k];
    if (parent < 0 || static_cast<std::size_t>(parent) >= leaf_of_row_.size()) continue;
    const std::int32_t leaf = leaf_of_row_[static_cast<std::size_t>(parent)];
    if (leaf < 0) continue;
    const Index row = first + static_cast<Index>(k);
    const std::int32_t e = static_cast<std::int32_t>(extra_row_.size());
    extra_row_.push_back(row);
    extra_next_.push_back(extra_head_[leaf]);
    extra_head_[leaf] = e;
    leaf_of_row_[static_cast<std::size_t>(row)] = leaf;
    ++extras_;
    ++live_;
    const Vec3 p = positions.row(row).transpose();
    const double r = radius_of(radii, row);
    Box& b = mut(leaf).box;
    if constexpr (Box::kContainsChildren) {
      if (std::is_same_v<Box, Aabb> && params_.update == UpdateMode::Bounded) {
        // Bounded boxes are anchored at different steps: a parent need not contain its child's box, so
        // every ancestor takes the ball (for boxes, a parent that contained its child still does).
        for (std::int32_t a = leaf; a >= 0; a = nodes_[a].parent) {
          if (!nodes_[a].box.contains(p, r)) {
            mut(a).box.expand(p, r);
            ++c.nu;
          }
        }
      } else if (!b.contains(p, r)) {
        b.expand(p, r);
        ++c.nu;
        grow_ancestors(leaf);
      }
    } else {
      // Parents need not contain their children here (see Obb): every ancestor is checked
      // against the new surfel itself.
      for (std::int32_t child = -1, a = leaf; a >= 0; child = a, a = nodes_[a].parent) {
        Box& box = mut(a).box;
        if (!box.contains(p, r)) {
          box.expand(p, r);
          ++c.nu;
        }
        if (child >= 0) box.grow_over_child(nodes_[child].box);  // still at least as large
      }
    }
    refit_since_build_ = true;
  }
  return c;
}

}  // namespace surfeledit::bvh
