// Fast generalized winding number of a surfel set (docs/algorithms.md §4.6): a binary tree over the
// surfels (median split of the longest box axis), each node with its area-weighted centroid c, summed
// dipole D = sum a_i n_i, second moment M = sum a_i n_i (p_i - c)^T and radius r = max |p_i - c|. A
// query takes a node's expansion to second order (with g(x) = x / (4 pi |x|^3) and x = c - q:
// D . g(x) + <M, dg/dx>) when |q - c| > beta r, else descends; leaves are summed exactly.
// Positions are kept relative to their centroid, so the result does not depend on where the set sits.
#include "surfeledit/core/winding.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

constexpr double kInvFourPi = 0.25 / 3.14159265358979323846;

struct Node {
  Vec3 center = Vec3::Zero();  // area-weighted centroid (local frame)
  Vec3 dipole = Vec3::Zero();  // sum a_i n_i
  Mat3 second = Mat3::Zero();  // sum a_i n_i (p_i - center)^T
  double radius = 0.0;         // max |p_i - center|
  Index begin = 0, end = 0;    // surfels order_[begin, end)
  Index left = -1, right = -1;  // children; -1 = leaf
};

// One surfel's (or node's) dipole term at q: D . (p - q) / (4 pi |p - q|^3); 0 at p itself.
inline double dipole_term(const Vec3& p, const Vec3& d, const Vec3& q) {
  const Vec3 r = p - q;
  const double r2 = r.squaredNorm();
  if (r2 == 0.0) return 0.0;
  return kInvFourPi * d.dot(r) / (r2 * std::sqrt(r2));
}

// A node's far-field expansion at q: D . g(x) + sum_jk M_jk dg_j/dx_k, x = c - q, where
// dg/dx = (I / |x|^3 - 3 x x^T / |x|^5) / (4 pi).
inline double far_field(const Node& n, const Vec3& q) {
  const Vec3 x = n.center - q;
  const double x2 = x.squaredNorm();
  const double inv3 = 1.0 / (x2 * std::sqrt(x2));
  const double first = n.dipole.dot(x) * inv3;
  const double second = n.second.trace() * inv3 - 3.0 * x.dot(n.second * x) * inv3 / x2;
  return kInvFourPi * (first + second);
}

}  // namespace

Values surfel_areas(const Points& positions, int k) {
  if (k < 1) throw Error(ErrorCode::InvalidArgument, "area_k", "must be >= 1, got " + std::to_string(k));
  const Index n = static_cast<Index>(positions.rows());
  Values out = Values::Zero(n);
  if (n < 2) return out;
  const int kk = std::min<Index>(k, n - 1);
  const KdTree tree(positions);
  const KnnResult nn = tree.knn(positions, kk + 1);  // the surfel itself first
  constexpr double kPi = 3.14159265358979323846;
  for (Index i = 0; i < n; ++i) out[i] = kPi * nn.dist2(i, kk) / (kk + 0.5);
  return out;
}

struct WindingNumber::Impl {
  WindingParams params;
  Vec3 origin = Vec3::Zero();  // centroid of the input; positions below are relative to it
  Points positions;            // #P by 3, local frame, in tree order
  Points dipoles;              // #P by 3: a_i n_i, in tree order
  std::vector<Node> nodes;     // nodes[0] = root

  Index build(Index begin, Index end, std::vector<Index>& order, const Points& local, const Points& dip) {
    const Index id = static_cast<Index>(nodes.size());
    nodes.emplace_back();
    Node node;
    node.begin = begin;
    node.end = end;
    double area = 0.0;
    Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300), mean = Vec3::Zero();
    for (Index q = begin; q < end; ++q) {
      const Vec3 p = local.row(order[q]).transpose();
      const Vec3 d = dip.row(order[q]).transpose();
      const double a = d.norm();
      node.dipole += d;
      node.center += a * p;
      area += a;
      mean += p;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    node.center = area > 0.0 ? Vec3(node.center / area) : Vec3(mean / static_cast<double>(end - begin));
    for (Index q = begin; q < end; ++q) {
      const Vec3 d = local.row(order[q]).transpose() - node.center;
      node.radius = std::max(node.radius, d.norm());
      node.second += dip.row(order[q]).transpose() * d.transpose();
    }
    if (end - begin > params.leaf_size) {
      int axis = 0;
      (hi - lo).maxCoeff(&axis);
      const Index mid = begin + (end - begin) / 2;
      std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                       [&](Index a, Index b) { return local(a, axis) < local(b, axis); });
      node.left = build(begin, mid, order, local, dip);
      node.right = build(mid, end, order, local, dip);
    }
    nodes[static_cast<std::size_t>(id)] = node;
    return id;
  }

  double at_local(const Vec3& q, double beta) const {
    if (nodes.empty()) return 0.0;
    double w = 0.0;
    Index stack[128];
    int top = 0;
    stack[top++] = 0;
    const double beta2 = beta * beta;
    while (top > 0) {
      const Node& n = nodes[static_cast<std::size_t>(stack[--top])];
      const double d2 = (q - n.center).squaredNorm();
      if (beta > 0.0 && d2 > beta2 * n.radius * n.radius) {
        w += far_field(n, q);
      } else if (n.left < 0 || top + 2 > 128) {
        for (Index i = n.begin; i < n.end; ++i)
          w += dipole_term(positions.row(i).transpose(), dipoles.row(i).transpose(), q);
      } else {
        stack[top++] = n.left;
        stack[top++] = n.right;
      }
    }
    return w;
  }
};

WindingNumber::WindingNumber(const Points& positions, const Points& normals, const Values& areas,
                             WindingParams params)
    : impl_(std::make_unique<Impl>()) {
  const Index n = static_cast<Index>(positions.rows());
  if (normals.rows() != n)
    throw Error(ErrorCode::InvalidArgument, "normals",
                "has " + std::to_string(normals.rows()) + " rows, positions has " + std::to_string(n));
  if (areas.size() != n)
    throw Error(ErrorCode::InvalidArgument, "areas",
                "has " + std::to_string(areas.size()) + " entries, positions has " + std::to_string(n));
  if (!(params.beta >= 0.0) || !std::isfinite(params.beta))
    throw Error(ErrorCode::InvalidArgument, "winding_beta", "must be finite and >= 0, got " + std::to_string(params.beta));
  if (params.leaf_size < 1)
    throw Error(ErrorCode::InvalidArgument, "leaf_size", "must be >= 1, got " + std::to_string(params.leaf_size));
  require_finite(positions, "positions");
  require_finite(normals, "normals");
  for (Index i = 0; i < n; ++i)
    if (!(areas[i] >= 0.0) || !std::isfinite(areas[i]))
      throw Error(ErrorCode::InvalidArgument, "areas", "must be finite and >= 0, got " + std::to_string(areas[i]));
  impl_->params = params;
  if (n == 0) return;
  impl_->origin = positions.colwise().mean().transpose();
  Points local = positions.rowwise() - impl_->origin.transpose();
  Points dip(n, 3);
  for (Index i = 0; i < n; ++i) dip.row(i) = areas[i] * normals.row(i);
  std::vector<Index> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  impl_->nodes.reserve(static_cast<std::size_t>(2 * n / std::max(1, params.leaf_size) + 2));
  impl_->build(0, n, order, local, dip);
  impl_->positions.resize(n, 3);
  impl_->dipoles.resize(n, 3);
  for (Index q = 0; q < n; ++q) {
    impl_->positions.row(q) = local.row(order[static_cast<std::size_t>(q)]);
    impl_->dipoles.row(q) = dip.row(order[static_cast<std::size_t>(q)]);
  }
}

WindingNumber::~WindingNumber() = default;
WindingNumber::WindingNumber(WindingNumber&&) noexcept = default;
WindingNumber& WindingNumber::operator=(WindingNumber&&) noexcept = default;

double WindingNumber::at(const Vec3& q) const { return impl_->at_local(q - impl_->origin, impl_->params.beta); }

double WindingNumber::at(const Vec3& q, double beta) const { return impl_->at_local(q - impl_->origin, beta); }

Values WindingNumber::at(const Points& queries, int threads) const {
  require_finite(queries, "queries");
  const Index n = static_cast<Index>(queries.rows());
  Values out(n);
  const int t = resolve_threads(threads);
#pragma omp parallel for schedule(dynamic, 256) num_threads(t)
  for (Index i = 0; i < n; ++i) out[i] = at(Vec3(queries.row(i).transpose()));
  return out;
}

Index WindingNumber::size() const { return static_cast<Index>(impl_->positions.rows()); }

std::size_t WindingNumber::memory_bytes() const {
  return sizeof(Impl) + impl_->nodes.capacity() * sizeof(Node) +
         static_cast<std::size_t>(impl_->positions.size() + impl_->dipoles.size()) * sizeof(double);
}

}  // namespace surfeledit
