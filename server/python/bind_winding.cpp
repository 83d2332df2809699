#include "surfeledit/core/winding.hpp"

#include "common.hpp"

namespace surfeledit::py {

void bind_winding(pyb::module_& m) {
  m.def(
      "winding_number",
      [](const pyb::handle& points, const pyb::handle& normals, const pyb::handle& areas, const pyb::handle& queries,
         double beta, int threads) {
        Points p = to_points(points, "points");
        Points n = to_points(normals, "normals");
        Values a = to_values(areas, "areas");
        Points q = to_points(queries, "queries");
        Values w;
        {
          pyb::gil_scoped_release release;
          WindingParams params;
          params.beta = beta;
          w = WindingNumber(p, n, a, params).at(q, threads);
        }
        return pyb::array_t<double>(static_cast<pyb::ssize_t>(w.size()), w.data());
      },
      pyb::arg("points"), pyb::arg("normals"), pyb::arg("areas"), pyb::arg("queries"), pyb::kw_only(),
      pyb::arg("beta") = 2.0, pyb::arg("threads") = 0,
      R"(Generalized winding number of oriented surfels (docs/algorithms.md §4.6): points, normals (P, 3),
areas (P,) model units squared, queries (Q, 3) -> (Q,) float64; beta: far-field acceptance (0 = exact).)");
  m.def(
      "surfel_areas",
      [](const pyb::handle& points, int k) {
        Points p = to_points(points, "points");
        Values a;
        {
          pyb::gil_scoped_release release;
          a = surfel_areas(p, k);
        }
        return pyb::array_t<double>(static_cast<pyb::ssize_t>(a.size()), a.data());
      },
      pyb::arg("points"), pyb::kw_only(), pyb::arg("k") = 8,
      R"(Area per surfel from the local density, pi d_k^2 / k (d_k: distance to the k-th nearest other
surfel): points (P, 3) -> (P,) model units squared.)");
}

}  // namespace surfeledit::py
