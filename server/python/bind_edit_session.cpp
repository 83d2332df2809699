#include "surfeledit/core/edit_session.hpp"

#include "surfeledit/core/settings.hpp"

#include "common.hpp"

namespace surfeledit::py {
namespace {

// A (K,) array of surfel ids: integers (a float id would be truncated to another surfel's), signed ones >= 0.
IdList to_ids(const pyb::handle& h, const char* field) {
  if (h.is_none()) return {};
  const pyb::array raw = pyb::array::ensure(h);
  if (!raw || raw.ndim() != 1) throw Error(ErrorCode::InvalidArgument, field, "expected a 1-D array of surfel ids");
  const char kind = raw.dtype().kind();
  if (raw.size() > 0 && kind != 'i' && kind != 'u')
    throw Error(ErrorCode::InvalidArgument, field,
                "expected integer surfel ids, got dtype " + pyb::str(raw.dtype()).cast<std::string>());
  if (kind == 'u') {
    const auto u = pyb::array_t<std::uint64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(raw);
    return IdList(u.data(), u.data() + u.shape(0));
  }
  auto a = pyb::array_t<std::int64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(raw);
  IdList ids(a.shape(0));
  for (pyb::ssize_t i = 0; i < a.shape(0); ++i) {
    if (a.data()[i] < 0) throw Error(ErrorCode::NotFound, field, "unknown surfel id " + std::to_string(a.data()[i]));
    ids[i] = static_cast<SurfelId>(a.data()[i]);
  }
  return ids;
}

pyb::array_t<std::uint64_t> ids_array(const IdList& ids) { return pyb::array_t<std::uint64_t>(ids.size(), ids.data()); }

// Curves as a list of {"points": #K by 3, "closed": bool}.
pyb::list curves_list(const std::vector<Curve>& curves) {
  pyb::list out;
  for (const Curve& c : curves) {
    pyb::dict d;
    d["points"] = c.points;
    d["closed"] = c.closed;
    out.append(d);
  }
  return out;
}

// A MergeOutcome (merge, boolean) as a dict.
pyb::dict merge_dict(const MergeOutcome& m) {
  pyb::dict d;
  d["removed"] = ids_array(m.removed);
  d["features"] = ids_array(m.features);
  d["moved"] = ids_array(m.moved);
  d["inserted"] = ids_array(m.inserted);
  d["curves"] = curves_list(m.curves);
  d["merge_ms"] = m.merge_ms;
  d["crease_ms"] = m.crease_ms;
  d["curves_ms"] = m.curves_ms;
  d["total_ms"] = m.total_ms;
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
  d["asleep"] = s.asleep;
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
      .def_readonly("response", &StepResult::response,
                    "'none', 'reported', 'cancelled' (colliding: what would have collided), 'backed_off' or 'merged'")
      .def_property_readonly("backoff", [](const StepResult& o) {
        pyb::dict d;
        d["iterations"] = o.backoff.iterations;
        d["kept"] = o.backoff.kept;
        d["final_depth"] = o.backoff.final_depth;
        return d;
      }, "back-off: iterations, kept (fraction of the step), final_depth (model units)")
      .def_property_readonly("features", [](const StepResult& o) { return ids_array(o.features); })
      .def_readonly("response_ms", &StepResult::response_ms)
      .def_readonly("history_ms", &StepResult::history_ms, "time of recording the step in the history")
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
          [](EditSession& s, const pyb::handle& zero, const pyb::handle& one, const std::string& author) {
            RegionSpec z{to_ids(zero, "zero"), {}}, o{to_ids(one, "one"), {}};
            pyb::gil_scoped_release release;
            s.set_regions(z, o, author);
          },
          pyb::kw_only(), pyb::arg("zero"), pyb::arg("one"), pyb::arg("author") = "",
          "Sets the zero and one regions of the tool of `author` (a client id; \"\" the default tool)")
      .def(
          "deform",
          [](EditSession& s, const Vec3& translation, const Vec3& axis, double angle, std::optional<Vec3> center,
             const std::string& blend, const std::string& author) {
            const DeformParams p = make_deform_params(translation, axis, angle, center, blend);
            pyb::gil_scoped_release release;
            return s.deform(p, author);
          },
          pyb::kw_only(), pyb::arg("translation") = Vec3::Zero(), pyb::arg("axis") = Vec3::UnitZ(),
          pyb::arg("angle") = 0.0, pyb::arg("center") = pyb::none(), pyb::arg("blend") = "smooth",
          pyb::arg("author") = "",
          "One step of the tool of `author`, then resampling and collision detection as configured; returns a "
          "StepResult")
      .def(
          "configure",
          [](EditSession& s, const pyb::kwargs& kwargs) {
            const std::vector<NamedSetting> changes = to_settings(kwargs);
            pyb::gil_scoped_release release;
            s.configure(changes);
          },
          configure_doc())
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
      .def(
          "merge",
          [](EditSession& s, bool crease) {
            MergeOutcome m;
            {
              pyb::gil_scoped_release release;
              m = s.merge(crease);
            }
            return merge_dict(m);
          },
          pyb::arg("crease") = true,
          "Merges the regions (§7 d): removed, features, moved, inserted (ids), curves, merge/crease/curves/total_ms")
      .def(
          "intersection_curves",
          [](const EditSession& s, double refine_angle) {
            CurveParams p;
            p.refine_angle = refine_angle;
            return curves_list(s.intersection_curves(p));
          },
          pyb::kw_only(), pyb::arg("refine_angle") = CurveParams{}.refine_angle,
          "Curves through the last merge's crease: [{points: #K by 3, closed}]")
      .def(
          "clips",
          [](const EditSession& s) -> pyb::object {
            if (!s.model().has_clips()) return pyb::none();
            return pyb::make_tuple(s.model().clip_points(), s.model().clip_dirs());
          },
          "Clip lines (points #P by 3, unit directions #P by 3; zero: unclipped), or None without clips")
      .def("undo", [](EditSession& s) { return s.undo(); }, "Undoes the last change; returns the new version")
      .def("release", [](EditSession& s, const std::string& author) { return s.release(author); },
           pyb::kw_only(), pyb::arg("author") = "",
           "Frees the regions, detector and lock of the tool of `author`; False (no change) when it has no regions")
      .def("redo", [](EditSession& s) { return s.redo(); }, "Redoes the last undone change; returns the new version")
      .def("history", [](const EditSession& s) {
        pyb::list out;
        for (const HistoryItem& h : s.history()) {
          pyb::dict d;
          d["version"] = h.version;
          d["op"] = h.op;
          d["client"] = h.author;
          d["touched"] = ids_array(h.touched);
          d["undone"] = h.undone;
          out.append(d);
        }
        return out;
      }, "History entries, oldest first: version, op, client, touched (ids), undone")
      .def_property_readonly("version", &EditSession::version)
      .def_property_readonly("state_hash", &EditSession::state_hash)
      .def(
          "blend",
          [](EditSession& s, int iterations, double range_factor, double dt, const std::string& repulsion,
             const std::string& weight, bool only_grow, bool adaptive, const std::string& neighbourhood,
             const pyb::handle& features, const std::string& projection) {
            BlendParams p;
            p.iterations = iterations;
            p.range_factor = range_factor;
            p.dt = dt;
            p.repulsion = parse_enum<RepulsionKind>(repulsion, "repulsion");
            p.weight = parse_enum<WeightKind>(weight, "weight");
            p.only_grow = only_grow;
            p.adaptive = adaptive;
            p.neighbours = parse_enum<NeighbourMode>(neighbourhood, "neighbourhood");
            p.projection = parse_enum<ProjectionKind>(projection, "projection");
            std::optional<IdList> f;
            if (!features.is_none()) f = to_ids(features, "features");
            BlendOutcome b;
            {
              pyb::gil_scoped_release release;
              b = s.blend(p, f);
            }
            pyb::dict d;
            d["particles"] = b.particles;
            d["moved"] = ids_array(b.moved);
            d["inserted"] = ids_array(b.inserted);
            d["removed"] = ids_array(b.removed);
            d["energy"] = pyb::array_t<double>(b.energy.size(), b.energy.data());
            d["substeps"] = b.substeps;
            d["ms"] = b.ms;
            return d;
          },
          pyb::kw_only(), pyb::arg("iterations") = BlendParams{}.iterations,
          pyb::arg("range_factor") = BlendParams{}.range_factor, pyb::arg("dt") = BlendParams{}.dt,
          pyb::arg("repulsion") = "weight", pyb::arg("weight") = "compact", pyb::arg("only_grow") = false,
          pyb::arg("adaptive") = false, pyb::arg("neighbourhood") = "cached", pyb::arg("features") = pyb::none(),
          pyb::arg("projection") = "mls",
          "Blend tool (§12.3): particles, moved, inserted, removed (ids), energy per iteration, substeps, ms")
      .def(
          "boolean",
          [](EditSession& s, const std::string& op, const pyb::handle& positions, const pyb::handle& normals,
             const pyb::handle& radii) {
            const BooleanOp o = parse_enum<BooleanOp>(op, "op");
            SurfelArrays a;
            a.positions = to_points(positions, "positions");
            a.normals = to_points(normals, "normals");
            if (!radii.is_none()) a.radii = to_values(radii, "radii");
            MergeOutcome m;
            {
              pyb::gil_scoped_release release;
              m = s.boolean(o, std::move(a));
            }
            return merge_dict(m);
          },
          pyb::arg("op"), pyb::arg("positions"), pyb::arg("normals"), pyb::arg("radii") = pyb::none(),
          "Boolean of the model (A) with B (§12.4.1): as merge(); removed = A's dropped ids, inserted = B's new ids")
      .def(
          "fill_holes",
          [](EditSession& s, double max_diameter, int iterations, const pyb::handle& boundary,
             const std::string& projection) {
            HoleParams p;
            p.max_diameter = max_diameter;
            p.iterations = iterations;
            p.projection = parse_enum<ProjectionKind>(projection, "projection");
            std::optional<IdList> b;
            if (!boundary.is_none()) b = to_ids(boundary, "boundary");
            FillOutcome f;
            {
              pyb::gil_scoped_release release;
              f = s.fill_holes(p, b);
            }
            pyb::list holes;
            for (const HoleOutcome& h : f.holes) {
              pyb::dict d;
              d["boundary"] = ids_array(h.boundary);
              d["diameter"] = h.diameter;
              d["inserted"] = ids_array(h.inserted);
              holes.append(d);
            }
            pyb::dict d;
            d["holes"] = holes;
            d["skipped"] = f.skipped;
            d["inserted"] = ids_array(f.inserted);
            d["ms"] = f.ms;
            return d;
          },
          pyb::arg("max_diameter"), pyb::kw_only(), pyb::arg("iterations") = HoleParams{}.iterations,
          pyb::arg("boundary") = pyb::none(), pyb::arg("projection") = "mls",
          "Hole filling (§12.4.2): holes [{boundary, diameter, inserted}], skipped, inserted (ids), ms")
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
        pyb::dict kinds;
        for (const auto& k : r.history_kinds) {
          pyb::dict one;
          one["entries"] = k.entries;
          one["bytes"] = k.bytes;
          kinds[pyb::str(k.kind)] = one;
        }
        d["history_kinds"] = kinds;
        return d;
      }, "What the session holds: surfels, structures {name: bytes}, total_bytes, bytes_per_surfel, "
         "hierarchy_status, history_kinds {rows|tool|whole|detectors: {entries, bytes}} (detectors: objects only the "
         "history keeps alive; entries counts them)");
}

}  // namespace surfeledit::py
