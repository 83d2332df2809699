#include "surfeledit/core/deformation.hpp"

#include <memory>

#include "common.hpp"

namespace surfeledit::py {

DeformParams make_deform_params(const Vec3& t, const Vec3& axis, double angle, const std::optional<Vec3>& center,
                                const std::string& blend) {
  DeformParams p;
  p.translation = t;
  p.axis = axis;
  p.angle = angle;
  p.center = center;
  p.blend = parse_blend(blend);
  validate(p);
  return p;
}

namespace {

// The deformation tool in-process over its own copy of positions and normals.
struct DeformationTool {
  Points positions, normals;
  DeformationFields fields;
  int threads = 1;
};

std::vector<Region> regions_from(Index n, const pyb::handle& zero, const pyb::handle& one) {
  std::vector<Region> r(static_cast<std::size_t>(n), Region::Blend);
  auto mark = [&](const pyb::handle& h, Region value, const char* field) {
    auto a = pyb::array_t<std::int64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(h);
    if (!a || a.ndim() != 1) throw Error(ErrorCode::InvalidArgument, field, "expected a 1-D array of row indices");
    for (pyb::ssize_t i = 0; i < a.shape(0); ++i) {
      const std::int64_t row = a.data()[i];
      if (row < 0 || row >= n) throw Error(ErrorCode::NotFound, field, "row " + std::to_string(row) + " out of range [0, " + std::to_string(n) + ")");
      if (r[row] != Region::Blend) throw Error(ErrorCode::Conflict, field, "row " + std::to_string(row) + " is in both regions");
      r[row] = value;
    }
  };
  mark(zero, Region::Zero, "zero");
  mark(one, Region::One, "one");
  return r;
}

}  // namespace

void bind_deformation(pyb::module_& m) {
  m.def(
      "blend_value", [](const std::string& blend, double lam) { return blend_value(parse_blend(blend), lam); },
      pyb::arg("blend"), pyb::arg("lam"), "beta(lambda) of a blend: 'smooth', 'quadratic' or 'linear'");
  pyb::class_<DeformationTool>(m, "DeformationTool", R"(The deformation tool (§1) in-process.

DeformationTool(positions (P, 3), normals (P, 3), zero=rows, one=rows): rows in neither region
blend between them. step(...) applies one cumulative step and returns the moved rows.)")
      .def(pyb::init([](const pyb::handle& positions, const pyb::handle& normals, const pyb::handle& zero,
                        const pyb::handle& one, int threads) {
             auto t = std::make_unique<DeformationTool>();
             t->positions = to_points(positions, "positions");
             t->normals = to_points(normals, "normals");
             if (t->normals.rows() != t->positions.rows())
               throw Error(ErrorCode::InvalidArgument, "normals", "row count differs from positions");
             require_finite(t->positions, "positions");
             require_finite(t->normals, "normals");
             t->normals.rowwise().normalize();
             t->threads = threads;
             const auto regions = regions_from(static_cast<Index>(t->positions.rows()), zero, one);
             pyb::gil_scoped_release release;
             t->fields = compute_fields(t->positions, regions, threads);
             return t;
           }),
           pyb::arg("positions"), pyb::arg("normals"), pyb::kw_only(), pyb::arg("zero"), pyb::arg("one"),
           pyb::arg("threads") = 1)
      .def(
          "step",
          [](DeformationTool& t, const Vec3& translation, const Vec3& axis, double angle, std::optional<Vec3> center,
             const std::string& blend) {
            const DeformParams p = make_deform_params(translation, axis, angle, center, blend);
            DeformResult r;
            {
              pyb::gil_scoped_release release;
              r = apply_step(t.fields, p, t.positions, t.normals, nullptr, nullptr, t.threads);
            }
            return pyb::array_t<Index>(r.moved.size(), r.moved.data());
          },
          pyb::kw_only(), pyb::arg("translation") = Vec3::Zero(), pyb::arg("axis") = Vec3::UnitZ(),
          pyb::arg("angle") = 0.0, pyb::arg("center") = pyb::none(), pyb::arg("blend") = "smooth")
      .def_readonly("positions", &DeformationTool::positions)
      .def_readonly("normals", &DeformationTool::normals)
      .def_property_readonly("lam", [](const DeformationTool& t) { return t.fields.lambda(); }, "lambda = d0 / (d0 + d1), (P,)")
      .def_property_readonly("grad_lam", [](const DeformationTool& t) { return t.fields.grad_lambda(); }, "gradient of lambda, (P, 3)")
      .def_property_readonly("regions", [](const DeformationTool& t) {
        pyb::array_t<std::uint8_t> out(t.fields.regions.size());
        for (std::size_t i = 0; i < t.fields.regions.size(); ++i) out.mutable_data()[i] = static_cast<std::uint8_t>(t.fields.regions[i]);
        return out;
      }, "per row: 0 zero, 1 blend, 2 one");
}

}  // namespace surfeledit::py
