// Clustering of surfels for surface simplification (docs/algorithms.md §6, thesis §9.2, Pauly et al. 2002):
// region growing (thesis §9.2.1) and hierarchical splitting (thesis §9.2.2). Both work on a subset of a
// model's rows (e.g. its deformable surfels) and put every listed row into exactly one cluster.
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {

// One node of the binary split tree of hierarchical clustering. Children are adjacent (first_child,
// first_child + 1) and come after their parent; a node covers the slots [begin, end) of
// Clustering::members; the leaves are the clusters.
struct ClusterTreeNode {
  std::int32_t first_child = -1;  // left child, the right one is first_child + 1; -1 = leaf
  std::int32_t parent = -1;       // -1 for the root
  std::int32_t begin = 0;         // first slot of Clustering::members under this node
  std::int32_t end = 0;           // one past the last slot
  std::int32_t cluster = -1;      // leaves: the cluster this leaf is; -1 for inner nodes
  std::int32_t level = 0;         // depth, root = 0
};

// Clusters in compressed form: cluster c holds the rows members[offsets[c] .. offsets[c+1]).
struct Clustering {
  IndexList members;                   // every clustered row exactly once, grouped by cluster
  std::vector<std::int64_t> offsets;   // #C + 1 slot offsets into members
  std::vector<ClusterTreeNode> tree;   // hierarchical clustering only: its split tree (empty otherwise)

  Index size() const { return offsets.empty() ? 0 : static_cast<Index>(offsets.size() - 1); }  // #C
  Index count(Index c) const { return static_cast<Index>(offsets[c + 1] - offsets[c]); }  // surfels in c
  const Index* rows(Index c) const { return members.data() + offsets[c]; }                 // its rows
};

// thesis §9.2.1: visiting `rows` in order, an unclustered surfel and its k - 1 nearest other listed surfels
// (k = cluster_size) become a new cluster if none of them is clustered yet. With max_variation < 1/3
// only the longest distance-ordered prefix of them whose variation stays <= max_variation is taken.
// Left-over ("stray") surfels then join the cluster of their nearest clustered surfel, so clusters may
// exceed k. Deterministic (sequential; the k-d tree queries are exact).
Clustering cluster_region_growing(const Points& positions, const IndexList& rows, const SimplifyParams& params);

// thesis §9.2.2: starting from all `rows`, a cluster is split at its centroid by the plane normal to its
// largest-variance axis while it holds more than cluster_size surfels or its variation exceeds
// max_variation (the thesis stops when either bound is met; we stop when both are, so the size bound
// always holds, as in Pauly et al.'s adaptive variant). Fills Clustering::tree.
Clustering cluster_hierarchical(const Points& positions, const IndexList& rows, const SimplifyParams& params);

// The clustering `params.method` names; None gives one cluster per row.
Clustering make_clusters(const Points& positions, const IndexList& rows, const SimplifyParams& params);

}  // namespace surfeledit
