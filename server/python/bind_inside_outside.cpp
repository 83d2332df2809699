#include "surfeledit/core/inside_outside.hpp"

#include "common.hpp"

namespace surfeledit::py {

void bind_inside_outside(pyb::module_& m) {
  m.def(
      "classify_inside",
      [](const pyb::handle& points, const pyb::handle& normals, const pyb::handle& queries, double threshold, int threads) {
        Points p = to_points(points, "points");
        Points n = to_points(normals, "normals");
        Points q = to_points(queries, "queries");
        if (n.rows() != p.rows())
          throw Error(ErrorCode::InvalidArgument, "normals", "has " + std::to_string(n.rows()) + " rows, points has " + std::to_string(p.rows()));
        if (p.rows() == 0) throw Error(ErrorCode::InvalidArgument, "points", "empty model");
        if (!std::isfinite(threshold)) throw Error(ErrorCode::InvalidArgument, "threshold", "must be finite, got " + std::to_string(threshold));
        std::vector<std::uint8_t> flags;
        {
          pyb::gil_scoped_release release;
          flags = classify_inside(p, n, q, InsideOutsideParams{threshold, threads});
        }
        pyb::array_t<bool> out(static_cast<pyb::ssize_t>(flags.size()));
        auto* o = out.mutable_data();
        for (std::size_t i = 0; i < flags.size(); ++i) o[i] = flags[i] != 0;
        return out;
      },
      pyb::arg("points"), pyb::arg("normals"), pyb::arg("queries"), pyb::kw_only(), pyb::arg("threshold") = 0.0,
      pyb::arg("threads") = 0,
      R"(Inside/outside test (§2): for each query point p1 with nearest surfel (p2, n2),
inside iff (p1 - p2) . n2 <= threshold. points, normals: (P, 3); queries: (Q, 3) -> (Q,) bool.)");
}

}  // namespace surfeledit::py
