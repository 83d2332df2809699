// Surfel -> cluster map for the lifetime of an edit (thesis §9.3): every clustered row belongs to
// exactly one cluster; rows appended later by dynamic resampling join the cluster of the surfel they
// were split from; removed rows leave theirs (a cluster may become empty and is then skipped).
#pragma once

#include <vector>

#include "surfeledit/core/simplify/clustering.hpp"

namespace surfeledit {

class ClusterMap {
 public:
  ClusterMap() = default;
  // Over a model of `rows` rows; the rows in `clusters` get their cluster, all others (e.g. zero
  // surfels) none (-1). Throws InvalidArgument if a row is out of range or listed twice.
  ClusterMap(Index rows, const Clustering& clusters);

  Index rows() const { return static_cast<Index>(cluster_of_.size()); }        // model rows tracked
  Index cluster_count() const { return static_cast<Index>(members_.size()); }  // clusters (empty ones too)
  Index cluster_of(Index row) const { return cluster_of_[row]; }              // -1 = in no cluster
  const IndexList& members(Index c) const { return members_[c]; }             // rows of cluster c

  // The model appended parents.size() rows after its existing ones; row rows() + k was split from
  // parents[k] and joins its cluster (or none if the parent has none).
  void on_inserted(const IndexList& parents);
  // The model dropped rows: `keep` has one flag per old row; kept rows are renumbered.
  void on_removed(const std::vector<bool>& keep);
  // Throws Internal unless every row's cluster lists it exactly once and nothing else is listed.
  void check() const;

 private:
  IndexList cluster_of_;               // #P: cluster of each row, -1 for none
  std::vector<IndexList> members_;     // #C: rows of each cluster, ascending
};

}  // namespace surfeledit
