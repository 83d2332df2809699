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

// Keyword arguments -> settings: bool -> bool, int/float -> number, str -> text.
std::vector<NamedSetting> to_settings(const pyb::kwargs& kwargs) {
  std::vector<NamedSetting> out;
  for (const auto& [key, value] : kwargs) {
    const std::string name = pyb::cast<std::string>(key);
    if (pyb::isinstance<pyb::bool_>(value)) {
      out.push_back({name, pyb::cast<bool>(value)});
    } else if (pyb::isinstance<pyb::int_>(value) || pyb::isinstance<pyb::float_>(value)) {
      out.push_back({name, pyb::cast<double>(value)});
    } else if (pyb::isinstance<pyb::str>(value)) {
      out.push_back({name, pyb::cast<std::string>(value)});
    } else {
      throw Error(ErrorCode::InvalidArgument, name,
                  "expects a bool, number or str, got " + std::string(pyb::str(pyb::type::handle_of(value).attr("__name__"))));
    }
  }
  return out;
}

pyb::dict settings_dict(const SessionSettings& settings) {
  pyb::dict d;
  for (const NamedSetting& s : describe(settings)) {
    if (const bool* b = std::get_if<bool>(&s.value)) {
      d[pyb::str(s.name)] = *b;
    } else if (const std::string* t = std::get_if<std::string>(&s.value)) {
      d[pyb::str(s.name)] = *t;
    } else {
      const double v = std::get<double>(s.value);
      const bool integral = s.name == "boundary_n" || s.name == "boundary_i" || s.name == "threads" ||
                            s.name == "leaf_max_surfels" || s.name == "leaf_min_surfels" || s.name == "max_level";
      if (integral) {
        d[pyb::str(s.name)] = static_cast<long long>(v);
      } else {
        d[pyb::str(s.name)] = v;
      }
    }
  }
  return d;
}

pyb::dict stats_dict(const CollisionStats& s) {
  pyb::dict d;
  d["deformable"] = s.deformable;
  d["tested"] = s.tested;
  d["queries"] = s.queries;
  d["colliding"] = s.colliding;
  d["detect_ms"] = s.detect_ms;
  d["preprocess_ms"] = s.preprocess_ms;
  d["nv"] = s.nv;
  d["np"] = s.np;
  d["nu"] = s.nu;
  return d;
}

}  // namespace

void bind_edit_session(pyb::module_& m) {
  pyb::class_<StepResult>(m, "StepResult", "What one deformation step did (in-process)")
      .def_readonly("seq", &StepResult::seq)
      .def_property_readonly("moved", [](const StepResult& o) { return o.moved.size(); }, "number of moved or split rows")
      .def_property_readonly("inserted", [](const StepResult& o) { return ids_array(o.inserted); })
      .def_property_readonly("center", [](const StepResult& o) { return o.center; })
      .def_readonly("detected", &StepResult::detected)
      .def_property_readonly("colliding", [](const StepResult& o) { return ids_array(o.colliding); })
      .def_property_readonly("depths",
                             [](const StepResult& o) { return pyb::array_t<double>(o.depths.size(), o.depths.data()); })
      .def_property_readonly("stats", [](const StepResult& o) { return stats_dict(o.stats); })
      .def_readonly("deform_ms", &StepResult::deform_ms)
      .def_readonly("resample_ms", &StepResult::resample_ms)
      .def("__repr__", [](const StepResult& o) {
        return "StepResult(seq=" + std::to_string(o.seq) + ", moved=" + std::to_string(o.moved.size()) +
               ", inserted=" + std::to_string(o.inserted.size()) + ", colliding=" + std::to_string(o.colliding.size()) + ")";
      });

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
            pyb::gil_scoped_release release;
            return s.deform(p);
          },
          pyb::kw_only(), pyb::arg("translation") = Vec3::Zero(), pyb::arg("axis") = Vec3::UnitZ(),
          pyb::arg("angle") = 0.0, pyb::arg("center") = pyb::none(), pyb::arg("blend") = "smooth",
          "One step, then resampling and collision detection as configured; returns a StepResult")
      .def(
          "configure",
          [](EditSession& s, const pyb::kwargs& kwargs) {
            const std::vector<NamedSetting> changes = to_settings(kwargs);
            pyb::gil_scoped_release release;
            s.configure(changes);
          },
          "Session settings by keyword (algorithm=, threshold=, boundary=, boundary_n=, boundary_i=, step_bound=, "
          "threads=, resample=, split_threshold=, zero_hierarchy=, deformable_hierarchy=, update=, hybrid_f=, sat=, "
          "extended=, leaf_max_surfels=, leaf_min_surfels=, max_level=, min_leaf_extent=, inflation=); validated before "
          "anything changes")
      .def("settings", [](const EditSession& s) { return settings_dict(s.settings()); })
      .def(
          "rebuild",
          [](EditSession& s) {
            pyb::gil_scoped_release release;
            return s.rebuild_hierarchies();
          },
          "Starts a background rebuild of the deformable tree (adopted at a later step, never waited for); "
          "False when there is none or one is under way")
      .def(
          "hierarchy",
          [](const EditSession& s) {
            const HierarchyInfo h = s.hierarchy_info();
            pyb::dict d;
            d["status"] = h.status;
            d["zero_build_ms"] = h.zero_build_ms;
            d["deformable_build_ms"] = h.deformable_build_ms;
            d["last_rebuild_ms"] = h.last_rebuild_ms;
            d["rebuilds_adopted"] = h.rebuilds_adopted;
            return d;
          },
          "Trees of the detector: status ('fresh' | 'refit' | 'rebuilding', '' without a hierarchy), build times, "
          "rebuilds adopted")
      .def("colliding", [](const EditSession& s) { return ids_array(s.colliding()); },
           "Colliding ids after the last step, ascending")
      .def(
          "remove",
          [](EditSession& s, const pyb::handle& ids) {
            const IdList list = to_ids(ids, "ids");
            pyb::gil_scoped_release release;
            s.remove(list);
          },
          pyb::arg("ids"))
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
        d["hierarchy_status"] = r.hierarchy_status;
        return d;
      }, "What the session holds: surfels, structures {name: bytes}, total_bytes, bytes_per_surfel");
}

}  // namespace surfeledit::py
