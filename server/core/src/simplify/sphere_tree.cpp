// Sphere cluster trees from hierarchical clustering and from region growing (see sphere_tree.hpp).
#include "surfeledit/core/simplify/sphere_tree.hpp"

#include <algorithm>
#include <chrono>
#include <limits>
#include <numeric>
#include <omp.h>

#include "surfeledit/core/simplify/clustering.hpp"
#include "surfeledit/core/simplify/miniball.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// A node of the bottom-up tree before it is laid out.
struct LooseNode {
  bvh::Sphere sphere;
  std::int32_t left = -1, right = -1;  // children (-1 = leaf)
  std::int32_t cluster = -1;           // leaves: cluster index
};

// Huffman-like pairing (thesis §9.4.2): merges the two entries of `group` whose merged sphere is smallest,
// until one is left; returns it. Pairwise merged radii are kept in a table, so each merge costs O(m)
// new sphere merges (O(m^2) over the node) plus a scan of the table.
std::int32_t pair_up(std::vector<LooseNode>& nodes, std::vector<std::int32_t> group) {
  const std::size_t m = group.size();
  if (m == 1) return group[0];
  std::vector<double> table(m * m, std::numeric_limits<double>::infinity());
  std::vector<char> alive(m, 1);
  auto merged_radius = [&](std::size_t a, std::size_t b) {
    return min_sphere_of_two(nodes[group[a]].sphere, nodes[group[b]].sphere).radius;
  };
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b) table[a * m + b] = merged_radius(a, b);
  for (std::size_t left = m; left > 1; --left) {
    std::size_t ba = 0, bb = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t a = 0; a < m; ++a) {
      if (!alive[a]) continue;
      for (std::size_t b = a + 1; b < m; ++b) {
        if (alive[b] && table[a * m + b] < best) {
          best = table[a * m + b];
          ba = a;
          bb = b;
        }
      }
    }
    LooseNode parent;
    parent.left = group[ba];
    parent.right = group[bb];
    parent.sphere = min_sphere_of_two(nodes[group[ba]].sphere, nodes[group[bb]].sphere);
    nodes.push_back(parent);
    // The parent takes slot ba; slot bb dies.
    group[ba] = static_cast<std::int32_t>(nodes.size() - 1);
    alive[bb] = 0;
    for (std::size_t c = 0; c < m; ++c) {
      if (!alive[c] || c == ba) continue;
      const double r = merged_radius(std::min(c, ba), std::max(c, ba));
      table[std::min(c, ba) * m + std::max(c, ba)] = r;
    }
  }
  for (std::size_t a = 0; a < m; ++a)
    if (alive[a]) return group[a];
  return -1;
}

}  // namespace

// Lays out trees in the shared flat form (friend of SphereClusterTree).
struct SphereTreeBuilder {
  // Breadth-first copy of a loose tree rooted at `root` (children adjacent), then slot ranges from the
  // leaves' cluster sizes, then order() from the clusters' rows.
  static void layout(SphereClusterTree& t, const std::vector<LooseNode>& loose, std::int32_t root,
                     const Clustering& clusters) {
    std::vector<SphereTreeNode>& out = t.nodes_;
    out.clear();
    std::vector<std::int32_t> source;  // flat index -> loose index
    out.emplace_back();
    source.push_back(root);
    for (std::size_t i = 0; i < out.size(); ++i) {
      const LooseNode& ln = loose[source[i]];
      out[i].sphere = ln.sphere;
      if (ln.left < 0) continue;
      const std::int32_t c = static_cast<std::int32_t>(out.size());
      out[i].first_child = c;
      for (std::int32_t child : {ln.left, ln.right}) {
        SphereTreeNode n;
        n.parent = static_cast<std::int32_t>(i);
        n.level = out[i].level + 1;
        out.push_back(n);
        source.push_back(child);
      }
    }
    // Sizes bottom-up (children come after parents), ranges top-down.
    std::vector<std::int32_t> size(out.size(), 0);
    for (std::size_t k = out.size(); k-- > 0;) {
      size[k] = out[k].first_child < 0 ? clusters.count(loose[source[k]].cluster)
                                       : size[out[k].first_child] + size[out[k].first_child + 1];
    }
    out[0].begin = 0;
    out[0].end = size[0];
    t.order_.assign(static_cast<std::size_t>(size[0]), -1);
    for (std::size_t k = 0; k < out.size(); ++k) {
      const SphereTreeNode& n = out[k];
      if (n.first_child < 0) {
        const std::int32_t c = loose[source[k]].cluster;
        std::copy(clusters.rows(c), clusters.rows(c) + clusters.count(c), t.order_.begin() + n.begin);
        continue;
      }
      SphereTreeNode& l = out[n.first_child];
      SphereTreeNode& r = out[n.first_child + 1];
      l.begin = n.begin;
      l.end = r.begin = n.begin + size[n.first_child];
      r.end = n.end;
    }
  }

  static SphereClusterTree hierarchical(const Points& positions, const Values& radii, const IndexList& rows,
                                        const SimplifyParams& params) {
    const auto start = std::chrono::steady_clock::now();
    SimplifyParams p = params;
    p.method = SimplifyMethod::Hierarchical;
    Clustering cl = cluster_hierarchical(positions, rows, p);
    SphereClusterTree t;
    t.cluster_ms_ = ms_since(start);
    if (cl.tree.empty()) {
      t.build_ms_ = ms_since(start);
      return t;
    }
    t.order_ = std::move(cl.members);
    t.nodes_.resize(cl.tree.size());
    for (std::size_t k = 0; k < cl.tree.size(); ++k) {
      const ClusterTreeNode& c = cl.tree[k];
      SphereTreeNode& n = t.nodes_[k];
      n.first_child = c.first_child;
      n.parent = c.parent;
      n.begin = c.begin;
      n.end = c.end;
      n.level = c.level;
    }
    // Leaves: minimal sphere of their surfels' balls (independent: multithreaded).
    const std::int32_t count = static_cast<std::int32_t>(t.nodes_.size());
    const int threads = resolve_threads(params.threads);
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
    for (std::int32_t k = 0; k < count; ++k) {
      SphereTreeNode& n = t.nodes_[k];
      if (n.first_child >= 0) continue;
      n.sphere = min_sphere_of_balls(positions, radii, t.order_.data() + n.begin, static_cast<std::size_t>(n.size()));
    }
    // Inner nodes: minimal sphere of their two children's spheres (children after parents).
    for (std::int32_t k = count; k-- > 0;) {
      SphereTreeNode& n = t.nodes_[k];
      if (n.first_child >= 0) n.sphere = min_sphere_of_two(t.nodes_[n.first_child].sphere, t.nodes_[n.first_child + 1].sphere);
    }
    t.build_ms_ = ms_since(start);
    return t;
  }

  static SphereClusterTree region_growing(const Points& positions, const Values& radii, const IndexList& rows,
                                          const SimplifyParams& params) {
    const auto start = std::chrono::steady_clock::now();
    SimplifyParams p = params;
    p.method = SimplifyMethod::RegionGrowing;
    const Clustering cl = cluster_region_growing(positions, rows, p);
    SphereClusterTree t;
    t.cluster_ms_ = ms_since(start);
    const Index leaves = cl.size();
    if (leaves == 0) {
      t.build_ms_ = ms_since(start);
      return t;
    }
    std::vector<LooseNode> loose(static_cast<std::size_t>(leaves));
    const int threads = resolve_threads(params.threads);
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
    for (Index c = 0; c < leaves; ++c) {
      loose[c].cluster = c;
      loose[c].sphere = min_sphere_of_balls(positions, radii, cl.rows(c), static_cast<std::size_t>(cl.count(c)));
    }
    // Cluster the current level's sphere centres again until one node is left (a k-ary tree), pairing
    // each k-ary node's children up into a binary subtree as it is formed.
    SimplifyParams up = params;
    up.cluster_size = std::max(2, params.cluster_size);
    up.max_variation = 1.0;
    std::vector<std::int32_t> level(static_cast<std::size_t>(leaves));
    std::iota(level.begin(), level.end(), 0);
    while (level.size() > 1) {
      const Index m = static_cast<Index>(level.size());
      Points centres(m, 3);
      for (Index k = 0; k < m; ++k) centres.row(k) = loose[level[k]].sphere.center.transpose();
      IndexList all(static_cast<std::size_t>(m));
      std::iota(all.begin(), all.end(), 0);
      const Clustering groups = cluster_region_growing(centres, all, up);
      std::vector<std::int32_t> next;
      next.reserve(static_cast<std::size_t>(groups.size()));
      for (Index g = 0; g < groups.size(); ++g) {
        std::vector<std::int32_t> members;
        for (Index k = 0; k < groups.count(g); ++k) members.push_back(level[groups.rows(g)[k]]);
        next.push_back(pair_up(loose, std::move(members)));
      }
      level = std::move(next);
    }
    layout(t, loose, level[0], cl);
    t.build_ms_ = ms_since(start);
    return t;
  }
};

SphereClusterTree SphereClusterTree::build_hierarchical(const Points& positions, const Values& radii,
                                                        const IndexList& rows, const SimplifyParams& params) {
  return SphereTreeBuilder::hierarchical(positions, radii, rows, params);
}

SphereClusterTree SphereClusterTree::build_region_growing(const Points& positions, const Values& radii,
                                                          const IndexList& rows, const SimplifyParams& params) {
  return SphereTreeBuilder::region_growing(positions, radii, rows, params);
}

Index SphereClusterTree::leaf_count() const {
  Index n = 0;
  for (const SphereTreeNode& node : nodes_) n += node.first_child < 0;
  return n;
}

int SphereClusterTree::height() const {
  int h = 0;
  for (const SphereTreeNode& node : nodes_) h = std::max(h, node.level + 1);
  return h;
}

void SphereClusterTree::check(const Points& positions, const Values& radii) const {
  auto fail = [](std::size_t k, const std::string& what) {
    throw Error(ErrorCode::Internal, "node " + std::to_string(k), what);
  };
  if (nodes_.empty()) return;
  if (nodes_[0].begin != 0 || nodes_[0].end != static_cast<std::int32_t>(order_.size())) fail(0, "root range");
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const SphereTreeNode& n = nodes_[k];
    if (n.begin > n.end || n.begin < 0) fail(k, "bad range");
    for (std::int32_t s = n.begin; s < n.end; ++s) {
      const Index r = order_[s];
      if (!n.sphere.contains(positions.row(r).transpose(), radii.size() ? radii[r] : 0.0)) fail(k, "misses a surfel");
    }
    if (n.first_child < 0) continue;
    if (n.first_child <= static_cast<std::int32_t>(k) || n.first_child + 1 >= static_cast<std::int32_t>(nodes_.size())) {
      fail(k, "children out of place");
    }
    const SphereTreeNode& l = nodes_[n.first_child];
    const SphereTreeNode& r = nodes_[n.first_child + 1];
    if (l.parent != static_cast<std::int32_t>(k) || r.parent != static_cast<std::int32_t>(k)) fail(k, "parent link");
    if (l.begin != n.begin || l.end != r.begin || r.end != n.end) fail(k, "children ranges");
    if (!n.sphere.contains(l.sphere) || !n.sphere.contains(r.sphere)) fail(k, "misses a child sphere");
  }
}

}  // namespace surfeledit
