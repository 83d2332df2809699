#include "surfeledit/core/model_io.hpp"

#include "common.hpp"

namespace surfeledit::py {

void bind_model_io(pyb::module_& m) {
  m.def(
      "load_file",
      [](const std::string& path, int normal_k) {
        SurfelArrays a;
        {
          pyb::gil_scoped_release release;
          a = load_surfels(path, LoadParams{normal_k});
        }
        if (a.radii.size() == 0) a.radii = estimate_radii(a.positions);
        pyb::dict d;
        d["positions"] = a.positions;
        d["normals"] = Points(a.normals.rowwise().normalized());
        d["radii"] = a.radii;
        if (a.colors.rows()) d["colors"] = a.colors;
        return d;
      },
      pyb::arg("path"), pyb::kw_only(), pyb::arg("normal_k") = 16,
      R"(Loads .ply / .pcd / .obj / ASCII .off / .stl, or a text point set (.xyz / .pwn: x y z [nx ny nz] per
line), into a dict of positions (P, 3), normals (P, 3), radii (P,) [, colors (P, 3) uint8]. Meshes give one surfel
per vertex with area-weighted normals; clouds without normals get estimated, consistently oriented ones.)");
  m.def(
      "save_file",
      [](const std::string& path, const pyb::handle& positions, const pyb::handle& normals, const pyb::handle& radii) {
        SurfelArrays a;
        a.positions = to_points(positions, "positions");
        a.normals = to_points(normals, "normals");
        if (!radii.is_none()) a.radii = to_values(radii, "radii");
        pyb::gil_scoped_release release;
        save_surfels(path, a);
      },
      pyb::arg("path"), pyb::arg("positions"), pyb::arg("normals"), pyb::arg("radii") = pyb::none(),
      "Saves surfels to .ply or .pcd (positions as float64).");
  m.def("estimate_radii", [](const pyb::handle& positions, int k) { return estimate_radii(to_points(positions, "positions"), k); },
        pyb::arg("positions"), pyb::kw_only(), pyb::arg("k") = 6, "Mean distance to the k nearest neighbours, (P,)");
}

}  // namespace surfeledit::py
