#include "surfeledit/core/kdtree.hpp"

#include "common.hpp"

namespace surfeledit::py {

void bind_kdtree(pyb::module_& m) {
  pyb::class_<KdTree>(m, "KdTree", R"(k-d tree over (P, 3) float64 points (exact; docs/algorithms.md §3).

knn(queries, k) -> (indices (Q, k) int32, dist2 (Q, k) float64): squared distances,
ascending; rows padded with -1 / inf when the tree has fewer than k points.
radius(queries, r) -> (list of Q int32 arrays, list of Q float64 dist2 arrays): all points
within real distance r, ascending.
align=True: a model tilted as a whole is searched in a turned frame along its surfaces (`axes`,
rows in world coordinates; the identity when not turned); its distances then round differently
(~1e-16 of the model's size).)")
      .def(pyb::init([](const pyb::handle& points, int leaf_size, int threads, bool align) {
             Points p = to_points(points, "points");
             if (leaf_size < 1) throw Error(ErrorCode::InvalidArgument, "leaf_size", "must be >= 1, got " + std::to_string(leaf_size));
             if (threads < 0) throw Error(ErrorCode::InvalidArgument, "threads", "must be >= 0, got " + std::to_string(threads));
             pyb::gil_scoped_release release;
             KdTreeParams params;
             params.leaf_size = leaf_size;
             params.threads = threads;
             params.align = align;
             return KdTree(p, params);
           }),
           pyb::arg("points"), pyb::kw_only(), pyb::arg("leaf_size") = 10, pyb::arg("threads") = 0,
           pyb::arg("align") = false)
      .def("__len__", &KdTree::size)
      .def_property_readonly("leaf_size", [](const KdTree& t) { return t.params().leaf_size; })
      .def_property_readonly("memory_bytes", &KdTree::memory_bytes)
      .def_property_readonly("axes", [](const KdTree& t) { return Eigen::Matrix<double, 3, 3, Eigen::RowMajor>(t.axes()); })
      .def(
          "knn",
          [](const KdTree& t, const pyb::handle& queries, int k) {
            if (k < 1) throw Error(ErrorCode::InvalidArgument, "k", "must be >= 1, got " + std::to_string(k));
            Points q = to_points(queries, "queries");
            KnnResult r;
            {
              pyb::gil_scoped_release release;
              r = t.knn(q, k);
            }
            return pyb::make_tuple(r.indices, r.dist2);
          },
          pyb::arg("queries"), pyb::arg("k"))
      .def(
          "radius",
          [](const KdTree& t, const pyb::handle& queries, double r) {
            if (!(r >= 0.0) || !std::isfinite(r)) throw Error(ErrorCode::InvalidArgument, "r", "must be finite and >= 0, got " + std::to_string(r));
            Points q = to_points(queries, "queries");
            RadiusResult res;
            {
              pyb::gil_scoped_release release;
              res = t.radius(q, r);
            }
            pyb::list idx, d2;
            for (std::size_t i = 0; i + 1 < res.offsets.size(); ++i) {
              const auto b = res.offsets[i], e = res.offsets[i + 1];
              pyb::array_t<Index> ai(e - b);
              pyb::array_t<double> ad(e - b);
              std::copy(res.indices.begin() + b, res.indices.begin() + e, ai.mutable_data());
              std::copy(res.dist2.begin() + b, res.dist2.begin() + e, ad.mutable_data());
              idx.append(ai);
              d2.append(ad);
            }
            return pyb::make_tuple(idx, d2);
          },
          pyb::arg("queries"), pyb::arg("r"));
}

}  // namespace surfeledit::py
