#include "surfeledit/core/edit_session.hpp"

#include "common.hpp"

namespace surfeledit::py {
namespace {

IdList to_ids(const pyb::handle& h, const char* field) {
  if (h.is_none()) return {};
  auto a = pyb::array_t<std::int64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(h);
  if (!a || a.ndim() != 1) throw Error(ErrorCode::InvalidArgument, field, "expected a 1-D array of surfel ids");
  IdList ids(a.shape(0));
  for (pyb::ssize_t i = 0; i < a.shape(0); ++i) {
    if (a.data()[i] < 0) throw Error(ErrorCode::NotFound, field, "unknown surfel id " + std::to_string(a.data()[i]));
    ids[i] = static_cast<SurfelId>(a.data()[i]);
  }
  return ids;
}

pyb::array_t<std::uint64_t> ids_array(const IdList& ids) { return pyb::array_t<std::uint64_t>(ids.size(), ids.data()); }

}  // namespace

void bind_edit_session(pyb::module_& m) {
  pyb::class_<EditSession>(m, "EditSession", "An editing session in-process (what the server holds per session)")
      .def(pyb::init([](const std::string& name, int threads) { return std::make_unique<EditSession>(name, SessionParams{threads}); }),
           pyb::arg("name") = "local", pyb::kw_only(), pyb::arg("threads") = 0)
      .def(
          "load_points",
          [](EditSession& s, const pyb::handle& positions, const pyb::handle& normals, const pyb::handle& radii) {
            SurfelArrays a;
            a.positions = to_points(positions, "positions");
            a.normals = to_points(normals, "normals");
            if (!radii.is_none()) a.radii = to_values(radii, "radii");
            pyb::gil_scoped_release release;
            s.load(SurfelModel::from_arrays(std::move(a)));
          },
          pyb::arg("positions"), pyb::arg("normals"), pyb::arg("radii") = pyb::none())
      .def(
          "set_regions",
          [](EditSession& s, const pyb::handle& zero, const pyb::handle& one) {
            RegionSpec z{to_ids(zero, "zero"), {}}, o{to_ids(one, "one"), {}};
            pyb::gil_scoped_release release;
            s.set_regions(z, o);
          },
          pyb::kw_only(), pyb::arg("zero"), pyb::arg("one"))
      .def(
          "deform",
          [](EditSession& s, const Vec3& translation, const Vec3& axis, double angle, std::optional<Vec3> center,
             const std::string& blend) {
            const DeformParams p = make_deform_params(translation, axis, angle, center, blend);
            StepOutcome r;
            {
              pyb::gil_scoped_release release;
              r = s.deform(p);
            }
            return r.moved.size();
          },
          pyb::kw_only(), pyb::arg("translation") = Vec3::Zero(), pyb::arg("axis") = Vec3::UnitZ(),
          pyb::arg("angle") = 0.0, pyb::arg("center") = pyb::none(), pyb::arg("blend") = "smooth",
          "One step; returns the number of moved surfels")
      .def_property_readonly("version", &EditSession::version)
      .def_property_readonly("state_hash", &EditSession::state_hash)
      .def("ids", [](const EditSession& s) { return ids_array(s.model().ids()); })
      .def("positions", [](const EditSession& s) { return s.model().positions(); })
      .def("normals", [](const EditSession& s) { return s.model().normals(); })
      .def("radii", [](const EditSession& s) { return s.model().radii(); })
      .def("report", [](const EditSession& s) {
        const SessionReport r = s.report();
        pyb::dict d, structures;
        for (const auto& st : r.structures) structures[pyb::str(st.name)] = st.bytes;
        d["surfels"] = r.surfels;
        d["structures"] = structures;
        d["total_bytes"] = r.total_bytes;
        d["bytes_per_surfel"] = r.bytes_per_surfel;
        return d;
      }, "What the session holds: surfels, structures {name: bytes}, total_bytes, bytes_per_surfel");
}

}  // namespace surfeledit::py
