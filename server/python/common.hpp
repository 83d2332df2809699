// Shared declarations of the pybind11 module surfeledit.core: one bind_* function per
// core concept (one file each), and numpy conversion helpers.
#pragma once

#include <Eigen/Dense>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::py {

namespace pyb = pybind11;

// (N, 3) float64 array -> Points, with a clear error naming `field` on a wrong shape.
Points to_points(const pyb::handle& a, const char* field);
// (N,) float64 array -> Values.
Values to_values(const pyb::handle& a, const char* field);

// Validated deformation step from the Python keyword arguments.
DeformParams make_deform_params(const Vec3& translation, const Vec3& axis, double angle,
                                const std::optional<Vec3>& center, const std::string& blend);

// Keyword arguments -> settings: bool -> bool, int -> integer, float -> number, str -> text
// (bind_settings.cpp).
std::vector<NamedSetting> to_settings(const pyb::kwargs& kwargs);
// A session's settings as {name: bool, int, float or str}.
pyb::dict settings_dict(const SessionSettings& settings);
// The docstring of EditSession.configure: one line per setting of the table.
const char* configure_doc();

void bind_errors(pyb::module_& m);
void bind_kdtree(pyb::module_& m);
void bind_inside_outside(pyb::module_& m);
void bind_winding(pyb::module_& m);
void bind_scene(pyb::module_& m);
void bind_deformation(pyb::module_& m);
void bind_model_io(pyb::module_& m);
void bind_settings(pyb::module_& m);
void bind_edit_session(pyb::module_& m);

}  // namespace surfeledit::py
