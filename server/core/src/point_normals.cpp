#include "point_normals.hpp"

#include <pcl/features/normal_3d_omp.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <tuple>
#include <vector>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

// Orients estimated normals consistently: a minimum spanning tree over the kNN graph
// with weight 1 - |ni . nj| (Hoppe et al. 1992), propagated from the highest point,
// whose normal is made to point up (+z), i.e. out of the model.
void orient_normals(const Points& p, Points& n, int k) {
  const Index count = static_cast<Index>(p.rows());
  if (count == 0) return;
  const KdTree tree(p);
  const int kk = std::min<int>(k + 1, count);
  const KnnResult nb = tree.knn(p, kk);
  Index root = 0;
  for (Index i = 1; i < count; ++i)
    if (p(i, 2) > p(root, 2)) root = i;
  if (n(root, 2) < 0) n.row(root) *= -1.0;

  std::vector<bool> done(count, false);
  using Item = std::tuple<double, Index, Index>;  // weight, node, parent
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  Index visited = 0;
  auto push_neighbours = [&](Index i) {
    for (int j = 0; j < kk; ++j) {
      const Index o = nb.indices(i, j);
      if (o < 0 || done[o]) continue;
      queue.emplace(1.0 - std::abs(n.row(i).dot(n.row(o))), o, i);
    }
  };
  // Several components: each new component starts from its highest remaining point.
  while (visited < count) {
    Index start = -1;
    for (Index i = 0; i < count; ++i)
      if (!done[i] && (start < 0 || p(i, 2) > p(start, 2))) start = i;
    if (start != root && n(start, 2) < 0.0) n.row(start) *= -1.0;
    done[start] = true;
    ++visited;
    push_neighbours(start);
    while (!queue.empty()) {
      const auto [w, i, parent] = queue.top();
      queue.pop();
      if (done[i]) continue;
      if (n.row(i).dot(n.row(parent)) < 0) n.row(i) *= -1.0;
      done[i] = true;
      ++visited;
      push_neighbours(i);
    }
  }
}

}  // namespace

Points estimate_normals(const Points& p, int k, const std::string& path) {
  if (p.rows() < 3) throw Error(ErrorCode::InvalidArgument, "path", "'" + path + "': too few points to estimate normals");
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  // PCL works in float: estimate in a local frame around the centroid to keep precision.
  const Eigen::RowVector3d c = p.colwise().mean();
  cloud->resize(p.rows());
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::RowVector3d q = p.row(i) - c;
    (*cloud)[i] = pcl::PointXYZ(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
  }
  pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setKSearch(std::min<int>(k, static_cast<int>(p.rows())));
  pcl::PointCloud<pcl::Normal> normals;
  ne.compute(normals);
  Points n(p.rows(), 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const auto& q = normals[i];
    n.row(i) << q.normal_x, q.normal_y, q.normal_z;
    if (!n.row(i).allFinite() || n.row(i).squaredNorm() < 1e-12) n.row(i) << 0, 0, 1;
  }
  orient_normals(p, n, k);
  return n;
}

}  // namespace surfeledit
