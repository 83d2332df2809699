#include "surfeledit/core/scene.hpp"

#include "common.hpp"

namespace surfeledit::py {
namespace {

// Lets a Python-owned solid (shared) be added to a Scene (which owns its parts).
class SharedSolid : public Solid {
 public:
  explicit SharedSolid(std::shared_ptr<Solid> s) : s_(std::move(s)) {}
  std::string kind() const override { return s_->kind(); }
  double sdf(const Vec3& p) const override { return s_->sdf(p); }
  SampledSurfels sample(const SampleParams& params) const override { return s_->sample(params); }
  double area() const override { return s_->area(); }

 private:
  std::shared_ptr<Solid> s_;
};

Pose make_pose(const pyb::handle& center, const pyb::handle& rotation) {
  Pose pose;
  if (!center.is_none()) {
    Points c = to_points(pyb::module_::import("numpy").attr("reshape")(center, pyb::make_tuple(1, 3)), "center");
    pose.translation = c.row(0).transpose();
  }
  if (!rotation.is_none()) {
    Points r = to_points(rotation, "rotation");
    if (r.rows() != 3) throw Error(ErrorCode::InvalidArgument, "rotation", "expected a (3, 3) rotation matrix");
    pose.rotation = r;
    if (!(pose.rotation.transpose() * pose.rotation).isApprox(Mat3::Identity(), 1e-9) || pose.rotation.determinant() < 0)
      throw Error(ErrorCode::InvalidArgument, "rotation", "not a proper rotation matrix");
  }
  require_finite(pose.translation.transpose(), "center");
  require_finite(pose.rotation, "rotation");
  return pose;
}

SampleParams sample_params(double spacing, std::uint64_t seed, double jitter) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) throw Error(ErrorCode::InvalidArgument, "spacing", "must be finite and > 0, got " + std::to_string(spacing));
  if (!(jitter >= 0.0 && jitter <= 0.5)) throw Error(ErrorCode::InvalidArgument, "jitter", "must be in [0, 0.5], got " + std::to_string(jitter));
  return SampleParams{spacing, seed, jitter};
}

Values sdf_of(const Solid& s, const Points& q) {
  Values out(q.rows());
  for (Eigen::Index i = 0; i < q.rows(); ++i) out[i] = s.sdf(q.row(i).transpose());
  return out;
}

}  // namespace

void bind_scene(pyb::module_& m) {
  pyb::class_<SampledSurfels>(m, "SampledSurfels", "Surface samples: positions (P, 3), normals (P, 3) unit outward, radii (P,), part (P,) int")
      .def_readonly("positions", &SampledSurfels::positions)
      .def_readonly("normals", &SampledSurfels::normals)
      .def_readonly("radii", &SampledSurfels::radii)
      .def_property_readonly("part", [](const SampledSurfels& s) { return pyb::array_t<int>(s.part.size(), s.part.data()); })
      .def("__len__", [](const SampledSurfels& s) { return s.positions.rows(); });

  pyb::class_<Solid, std::shared_ptr<Solid>>(m, "Solid", "Closed analytic solid with an exact signed distance (negative inside)")
      .def_property_readonly("kind", &Solid::kind)
      .def_property_readonly("area", &Solid::area)
      .def(
          "sdf",
          [](const Solid& s, const pyb::handle& q) {
            Points p = to_points(q, "queries");
            pyb::gil_scoped_release release;
            return sdf_of(s, p);
          },
          pyb::arg("queries"), "Signed distances (Q,) of (Q, 3) points")
      .def(
          "sample",
          [](const Solid& s, double spacing, std::uint64_t seed, double jitter) {
            const SampleParams sp = sample_params(spacing, seed, jitter);
            pyb::gil_scoped_release release;
            return s.sample(sp);
          },
          pyb::kw_only(), pyb::arg("spacing"), pyb::arg("seed") = 1, pyb::arg("jitter") = 0.25);

  const auto center = pyb::arg("center") = pyb::none();
  const auto rotation = pyb::arg("rotation") = pyb::none();
  m.def("make_sphere", [](double r, const pyb::handle& c, const pyb::handle& rot) { return std::shared_ptr<Solid>(make_sphere(r, make_pose(c, rot))); },
        pyb::arg("radius"), pyb::kw_only(), center, rotation);
  m.def("make_box", [](const Vec3& h, const pyb::handle& c, const pyb::handle& rot) { return std::shared_ptr<Solid>(make_box(h, make_pose(c, rot))); },
        pyb::arg("half_extents"), pyb::kw_only(), center, rotation);
  m.def("make_cylinder", [](double r, double hh, const pyb::handle& c, const pyb::handle& rot) { return std::shared_ptr<Solid>(make_cylinder(r, hh, make_pose(c, rot))); },
        pyb::arg("radius"), pyb::arg("half_height"), pyb::kw_only(), center, rotation);
  m.def("make_torus", [](double R, double r, const pyb::handle& c, const pyb::handle& rot) { return std::shared_ptr<Solid>(make_torus(R, r, make_pose(c, rot))); },
        pyb::arg("major_radius"), pyb::arg("minor_radius"), pyb::kw_only(), center, rotation);
  m.def("make_capsule", [](double r, double hl, const pyb::handle& c, const pyb::handle& rot) { return std::shared_ptr<Solid>(make_capsule(r, hl, make_pose(c, rot))); },
        pyb::arg("radius"), pyb::arg("half_length"), pyb::kw_only(), center, rotation);
  m.def("make_cup",
        [](double r, double h, double wall, double hm, double hn, const pyb::handle& c, const pyb::handle& rot) {
          return std::shared_ptr<Solid>(make_cup(r, h, wall, hm, hn, make_pose(c, rot)));
        },
        pyb::kw_only(), pyb::arg("radius") = 0.5, pyb::arg("height") = 1.0, pyb::arg("wall") = 0.08,
        pyb::arg("handle_major") = 0.25, pyb::arg("handle_minor") = 0.05, center, rotation);

  pyb::class_<Scene, std::unique_ptr<Scene>>(m, "Scene", "Union of solids; part i of a sample came from the i-th added solid")
      .def(pyb::init<>())
      .def("add", [](Scene& s, std::shared_ptr<Solid> solid) { s.add(std::make_unique<SharedSolid>(std::move(solid))); }, pyb::arg("solid"))
      .def_property_readonly("parts", &Scene::parts)
      .def(
          "sdf",
          [](const Scene& s, const pyb::handle& q, int part) {
            Points p = to_points(q, "queries");
            if (part >= static_cast<int>(s.parts())) throw Error(ErrorCode::InvalidArgument, "part", "scene has " + std::to_string(s.parts()) + " parts");
            pyb::gil_scoped_release release;
            return s.sdf(p, part);
          },
          pyb::arg("queries"), pyb::kw_only(), pyb::arg("part") = -1, "Signed distances (Q,) to one part, or to the union (part=-1)")
      .def(
          "sample",
          [](const Scene& s, double spacing, std::uint64_t seed, double jitter) {
            const SampleParams sp = sample_params(spacing, seed, jitter);
            pyb::gil_scoped_release release;
            return s.sample(sp);
          },
          pyb::kw_only(), pyb::arg("spacing"), pyb::arg("seed") = 1, pyb::arg("jitter") = 0.25);

  m.def("make_default_scene", [] { return std::make_unique<Scene>(make_default_scene()); }, "The demo scene: part 0 a rigid slab, part 1 a sphere above it");
}

}  // namespace surfeledit::py
