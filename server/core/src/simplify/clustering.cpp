// Region-growing and hierarchical clustering (see clustering.hpp).
#include "surfeledit/core/simplify/clustering.hpp"

#include <algorithm>
#include <numeric>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/simplify/surface_variation.hpp"

namespace surfeledit {

namespace {

// Longest prefix (at least min(3, n)) of rows[0 .. n) whose variation is <= max_variation. Sets of up to
// three points are planar (variation 0), so the bound only bites from four on.
std::size_t variation_prefix(const Points& positions, const Index* rows, std::size_t n, double max_variation) {
  if (max_variation >= 1.0 / 3.0) return n;
  std::size_t m = std::min<std::size_t>(3, n);
  while (m < n && surface_variation(positions, rows, m + 1) <= max_variation) ++m;
  return m;
}

Clustering to_csr(const IndexList& rows, const IndexList& cluster_of_slot, Index clusters) {
  Clustering out;
  out.offsets.assign(static_cast<std::size_t>(clusters) + 1, 0);
  for (Index c : cluster_of_slot) ++out.offsets[c + 1];
  for (Index c = 0; c < clusters; ++c) out.offsets[c + 1] += out.offsets[c];
  std::vector<std::int64_t> fill(out.offsets.begin(), out.offsets.end() - 1);
  out.members.resize(rows.size());
  for (std::size_t s = 0; s < rows.size(); ++s) out.members[fill[cluster_of_slot[s]]++] = rows[s];
  return out;
}

}  // namespace

Clustering cluster_region_growing(const Points& positions, const IndexList& rows, const SimplifyParams& params) {
  validate(params);
  Clustering out;
  out.offsets.push_back(0);
  if (rows.empty()) return out;
  const Index n = static_cast<Index>(rows.size());
  // Slot s = rows[s]; the tree answers with model rows, mapped back to slots.
  const Index max_row = *std::max_element(rows.begin(), rows.end());
  IndexList slot_of_row(static_cast<std::size_t>(max_row) + 1, -1);
  for (Index s = 0; s < n; ++s) {
    if (rows[s] < 0 || rows[s] >= positions.rows() || slot_of_row[rows[s]] >= 0) {
      throw Error(ErrorCode::InvalidArgument, "rows", "row out of range or listed twice");
    }
    slot_of_row[rows[s]] = s;
  }
  const KdTree tree(positions, rows);
  const int k = std::min<int>(params.cluster_size, n);
  IndexList cluster_of(static_cast<std::size_t>(n), -1);  // by slot
  Index clusters = 0;
  IndexList nn;
  std::vector<double> dist2;
  IndexList stray;
  for (Index s = 0; s < n; ++s) {
    if (cluster_of[s] >= 0) continue;
    tree.knn(positions.row(rows[s]).transpose(), k, nn, dist2);
    // The query point itself comes first unless a duplicate position ties with it: put it first.
    auto self = std::find(nn.begin(), nn.end(), rows[s]);
    if (self == nn.end()) {
      nn.insert(nn.begin(), rows[s]);
      nn.pop_back();
    } else {
      std::rotate(nn.begin(), self, self + 1);
    }
    const std::size_t m = variation_prefix(positions, nn.data(), nn.size(), params.max_variation);
    bool free = true;
    for (std::size_t j = 0; j < m && free; ++j) free = cluster_of[slot_of_row[nn[j]]] < 0;
    if (!free) {
      stray.push_back(s);
      continue;
    }
    for (std::size_t j = 0; j < m; ++j) cluster_of[slot_of_row[nn[j]]] = clusters;
    ++clusters;
  }
  // Stray surfels (still unclustered: a later cluster may have taken a skipped surfel) join the cluster
  // of their nearest clustered surfel. Every stray has one among its k nearest (that is why it was
  // skipped), so the first clustered one in distance order is the nearest clustered overall.
  IndexList join(stray.size(), -1);
  for (std::size_t j = 0; j < stray.size(); ++j) {
    const Index s = stray[j];
    if (cluster_of[s] >= 0) continue;  // taken by a later cluster after it was skipped
    tree.knn(positions.row(rows[s]).transpose(), k, nn, dist2);
    for (Index r : nn) {
      const Index c = cluster_of[slot_of_row[r]];
      if (c >= 0) {
        join[j] = c;
        break;
      }
    }
    if (join[j] < 0) {  // only possible with ties at the k-th distance; widen the search
      tree.knn(positions.row(rows[s]).transpose(), n, nn, dist2);
      for (Index r : nn) {
        const Index c = cluster_of[slot_of_row[r]];
        if (c >= 0) {
          join[j] = c;
          break;
        }
      }
    }
  }
  // Assigned after the search so that a stray never joins through another stray.
  for (std::size_t j = 0; j < stray.size(); ++j)
    if (join[j] >= 0) cluster_of[stray[j]] = join[j];
  for (Index s = 0; s < n; ++s)
    if (cluster_of[s] < 0) throw Error(ErrorCode::Internal, "rows", "region growing left a surfel unclustered");
  return to_csr(rows, cluster_of, clusters);
}

Clustering cluster_hierarchical(const Points& positions, const IndexList& rows, const SimplifyParams& params) {
  validate(params);
  Clustering out;
  out.members = rows;
  out.offsets.push_back(0);
  if (rows.empty()) return out;
  for (Index r : rows)
    if (r < 0 || r >= positions.rows()) throw Error(ErrorCode::InvalidArgument, "rows", "row out of range");
  const std::int32_t n = static_cast<std::int32_t>(rows.size());
  const std::int32_t max_size = params.cluster_size;
  const bool bound_variation = params.max_variation < 1.0 / 3.0;
  std::vector<ClusterTreeNode>& nodes = out.tree;
  nodes.reserve(static_cast<std::size_t>(4 * (n / std::max(1, max_size)) + 2));
  ClusterTreeNode root;
  root.begin = 0;
  root.end = n;
  nodes.push_back(root);
  std::vector<std::int32_t> stack{0};
  Index* slots = out.members.data();
  while (!stack.empty()) {
    const std::int32_t i = stack.back();
    stack.pop_back();
    const std::int32_t begin = nodes[i].begin, end = nodes[i].end, count = end - begin;
    if (count <= 1) continue;
    const Covariance cov = covariance_of(positions, slots + begin, static_cast<std::size_t>(count));
    if (count <= max_size && (!bound_variation || cov.variation() <= params.max_variation)) continue;
    const Vec3 axis = cov.largest_axis();
    const double at = cov.centroid.dot(axis);
    Index* mid = std::partition(slots + begin, slots + end,
                                [&](Index r) { return positions.row(r).dot(axis) < at; });
    std::int32_t cut = static_cast<std::int32_t>(mid - slots);
    if (cut == begin || cut == end) {
      // All on one side (coincident points): split by rank instead.
      cut = begin + count / 2;
      std::nth_element(slots + begin, slots + cut, slots + end, [&](Index a, Index b) {
        const double pa = positions.row(a).dot(axis), pb = positions.row(b).dot(axis);
        return pa < pb || (pa == pb && a < b);
      });
    }
    const std::int32_t c = static_cast<std::int32_t>(nodes.size());
    nodes[i].first_child = c;
    ClusterTreeNode left, right;
    left.parent = right.parent = i;
    left.level = right.level = nodes[i].level + 1;
    left.begin = begin;
    left.end = right.begin = cut;
    right.end = end;
    nodes.push_back(left);
    nodes.push_back(right);
    stack.push_back(c + 1);
    stack.push_back(c);
  }
  // Leaves in slot order are the clusters (the depth-first build visits left before right).
  IndexList leaves;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    if (nodes[k].first_child < 0) leaves.push_back(static_cast<Index>(k));
  std::sort(leaves.begin(), leaves.end(), [&](Index a, Index b) { return nodes[a].begin < nodes[b].begin; });
  for (std::size_t c = 0; c < leaves.size(); ++c) {
    nodes[leaves[c]].cluster = static_cast<std::int32_t>(c);
    out.offsets.push_back(nodes[leaves[c]].end);
  }
  return out;
}

Clustering make_clusters(const Points& positions, const IndexList& rows, const SimplifyParams& params) {
  validate(params);
  switch (params.method) {
    case SimplifyMethod::RegionGrowing: return cluster_region_growing(positions, rows, params);
    case SimplifyMethod::Hierarchical: return cluster_hierarchical(positions, rows, params);
    case SimplifyMethod::None: break;
  }
  Clustering out;
  out.members = rows;
  out.offsets.resize(rows.size() + 1);
  std::iota(out.offsets.begin(), out.offsets.end(), std::int64_t{0});
  return out;
}

}  // namespace surfeledit
