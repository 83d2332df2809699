#include "surfeledit/core/simplify/cluster_map.hpp"

#include <algorithm>

namespace surfeledit {

ClusterMap::ClusterMap(Index rows, const Clustering& clusters) {
  cluster_of_.assign(static_cast<std::size_t>(rows), -1);
  members_.resize(static_cast<std::size_t>(clusters.size()));
  for (Index c = 0; c < clusters.size(); ++c) {
    const Index* r = clusters.rows(c);
    for (Index k = 0; k < clusters.count(c); ++k) {
      if (r[k] < 0 || r[k] >= rows || cluster_of_[r[k]] >= 0) {
        throw Error(ErrorCode::InvalidArgument, "clusters", "row out of range or in two clusters");
      }
      cluster_of_[r[k]] = c;
    }
    members_[c].assign(r, r + clusters.count(c));
    std::sort(members_[c].begin(), members_[c].end());
  }
}

void ClusterMap::on_inserted(const IndexList& parents) {
  const Index base = rows();
  for (Index q : parents)
    if (q < 0 || q >= base) throw Error(ErrorCode::InvalidArgument, "parents", "parent row out of range");
  for (std::size_t k = 0; k < parents.size(); ++k) {
    const Index c = cluster_of_[parents[k]];
    cluster_of_.push_back(c);
    if (c >= 0) members_[c].push_back(base + static_cast<Index>(k));  // stays ascending: appended rows are last
  }
}

void ClusterMap::on_removed(const std::vector<bool>& keep) {
  if (keep.size() != cluster_of_.size()) throw Error(ErrorCode::Internal, "keep", "row count differs");
  IndexList new_row(keep.size(), -1);
  Index j = 0;
  for (std::size_t r = 0; r < keep.size(); ++r)
    if (keep[r]) new_row[r] = j++;
  for (IndexList& m : members_) {
    std::size_t w = 0;
    for (Index r : m)
      if (keep[r]) m[w++] = new_row[r];
    m.resize(w);
  }
  std::size_t w = 0;
  for (std::size_t r = 0; r < keep.size(); ++r)
    if (keep[r]) cluster_of_[w++] = cluster_of_[r];
  cluster_of_.resize(w);
}

void ClusterMap::check() const {
  std::vector<int> seen(cluster_of_.size(), 0);
  for (Index c = 0; c < cluster_count(); ++c) {
    for (Index r : members_[c]) {
      if (r < 0 || r >= rows() || cluster_of_[r] != c) throw Error(ErrorCode::Internal, "clusters", "member mismatch");
      ++seen[r];
    }
  }
  for (Index r = 0; r < rows(); ++r) {
    if ((cluster_of_[r] >= 0) != (seen[r] == 1) || seen[r] > 1) {
      throw Error(ErrorCode::Internal, "clusters", "row " + std::to_string(r) + " not in exactly its one cluster");
    }
  }
}

}  // namespace surfeledit
