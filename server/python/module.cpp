// surfeledit.core: the geometric core in-process (k-d tree, inside/outside, scene
// generator, deformation tool, model I/O, edit session). numpy in and out; heavy calls
// release the GIL; core errors surface as surfeledit.errors exceptions.
#include "common.hpp"

namespace surfeledit::py {

Points to_points(const pyb::handle& h, const char* field) {
  auto a = pyb::array_t<double, pyb::array::c_style | pyb::array::forcecast>::ensure(h);
  if (!a) throw Error(ErrorCode::InvalidArgument, field, "expected a numeric array of shape (N, 3)");
  if (a.ndim() == 1 && a.shape(0) == 0) return Points(0, 3);
  if (a.ndim() != 2 || a.shape(1) != 3) {
    std::string shape = "(";
    for (pyb::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
    throw Error(ErrorCode::InvalidArgument, field, "expected shape (N, 3), got " + shape + ")");
  }
  return Eigen::Map<const Points>(a.data(), a.shape(0), 3);
}

Values to_values(const pyb::handle& h, const char* field) {
  auto a = pyb::array_t<double, pyb::array::c_style | pyb::array::forcecast>::ensure(h);
  if (!a || a.ndim() != 1) throw Error(ErrorCode::InvalidArgument, field, "expected a 1-D numeric array of shape (N,)");
  return Eigen::Map<const Values>(a.data(), a.shape(0));
}

}  // namespace surfeledit::py

PYBIND11_MODULE(core, m) {
  using namespace surfeledit::py;
  m.doc() = "surfeledit geometric core (in-process): KdTree, classify_inside, scenes, deformation, I/O";
  bind_errors(m);
  bind_kdtree(m);
  bind_inside_outside(m);
  bind_scene(m);
  bind_deformation(m);
  bind_model_io(m);
  bind_settings(m);
  bind_edit_session(m);
  bind_winding(m);
}
