// Snapshots of the kernels' per-point states (row_detector.hpp's put_states / get_states): one
// put_state / get_state pair per kernel State, field by field (internal header).
#pragma once

#include "robust_kernel.hpp"
#include "simple_kernel.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "temporal_kernel.hpp"

namespace surfeledit::detail {

inline void put_vec3(SnapshotWriter& out, const Vec3& v) {
  out.f64(v.x());
  out.f64(v.y());
  out.f64(v.z());
}
inline Vec3 get_vec3(SnapshotReader& in, const char* what) {
  const double x = in.f64(what), y = in.f64(what), z = in.f64(what);
  return Vec3(x, y, z);
}
inline void put_sphere(SnapshotWriter& out, const Sphere& s) {
  put_vec3(out, s.center);
  out.f64(s.rho2);
}
inline void get_sphere(SnapshotReader& in, Sphere& s) {
  s.center = get_vec3(in, "sphere centre");
  s.rho2 = in.f64("sphere rho2");
}

inline void put_state(SnapshotWriter& out, const SimpleKernel::State& s) {
  out.f64(s.depth);
  out.u8(s.hit);
  out.u8(s.unbounded);
}
inline void get_state(SnapshotReader& in, SimpleKernel::State& s) {
  s.depth = in.f64("depth");
  s.hit = in.u8("hit");
  s.unbounded = in.u8("unbounded");
}

inline void put_state(SnapshotWriter& out, const TemporalKernel::State& s) {
  put_sphere(out, s.sphere);
  out.f64(s.depth);
  out.u8(s.hit);
  out.u8(s.unbounded);
}
inline void get_state(SnapshotReader& in, TemporalKernel::State& s) {
  get_sphere(in, s.sphere);
  s.depth = in.f64("depth");
  s.hit = in.u8("hit");
  s.unbounded = in.u8("unbounded");
}

// A row detector's Robust state holds no old position (RobustState); its leaf is not kept (a stale one costs time).
inline void put_state(SnapshotWriter& out, const RobustState& s) {
  put_sphere(out, s.sphere);
  out.u8(s.flags);
}
inline void get_state(SnapshotReader& in, RobustState& s) {
  get_sphere(in, s.sphere);
  s.flags = in.u8("flags");
  if (s.flags & RobustFlags::kOldHeld) in.fail("flags", "an old position held by a row detector's state");
}

}  // namespace surfeledit::detail
