// Analytic closed solids: exact signed distances and surface sampling with exact normals.
//
// Every surface is sampled in its parameter space, so samples lie exactly on it:
//  - curved pieces are "revolved profile segments": a 2-D curve in the (rho, z) half-plane of a
//    local axis frame, cut into rings of equal arc length (about one spacing apart), each ring cut
//    into round(arc / spacing) samples; density is then ~1 / spacing^2;
//  - box faces are regular grids.
// Jitter moves a sample inside its own parameter cell (fraction of the cell size), so it never
// crosses a face edge. Randomness: std::mt19937_64 from the seed, mapped to doubles by hand
// (not std::uniform_real_distribution) so samples are identical on every standard library.
#include "surfeledit/core/scene.hpp"

#include "solid_sampling.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace surfeledit {

namespace {

// Above this many estimated samples, sampling is refused (TooLarge).
constexpr double kMaxSamples = 2e7;

using solid_sampling::Frame;
using solid_sampling::kPi;
using solid_sampling::ProfilePoint;
using solid_sampling::Rng;
using solid_sampling::Sample;
using solid_sampling::sample_arc;
using solid_sampling::sample_segment;

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

void require_positive(double v, const char* field) {
  if (!std::isfinite(v) || v <= 0.0) {
    throw Error(ErrorCode::InvalidArgument, field, "must be finite and > 0, got " + fmt(v));
  }
}

void require_pose(const Pose& pose) {
  require_finite(pose.rotation, "pose.rotation");
  require_finite(pose.translation, "pose.translation");
  const double orth = (pose.rotation.transpose() * pose.rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-9 || pose.rotation.determinant() < 0.0) {
    throw Error(ErrorCode::InvalidArgument, "pose.rotation",
                "must be a proper rotation (orthonormal, det +1); |R^T R - I|max = " + fmt(orth));
  }
}

void require_sample_params(const SampleParams& params, double area) {
  require_positive(params.spacing, "spacing");
  if (!std::isfinite(params.jitter) || params.jitter < 0.0 || params.jitter > 0.5) {
    throw Error(ErrorCode::InvalidArgument, "jitter", "must be in [0, 0.5], got " + fmt(params.jitter));
  }
  const double estimate = area / (params.spacing * params.spacing);
  if (estimate > kMaxSamples) {
    throw Error(ErrorCode::TooLarge, "spacing",
                "spacing " + fmt(params.spacing) + " would give about " + fmt(std::round(estimate)) +
                    " samples (limit " + fmt(kMaxSamples) + ")");
  }
}

// Signed distance (negative inside) of a 2-D point to an axis-aligned rectangle of half extents (hx, hy).
double rect_sdf(double x, double y, double hx, double hy) {
  const double qx = std::abs(x) - hx, qy = std::abs(y) - hy;
  return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
}

// Distance of 2-D point (x, y) to the segment (ax, ay)-(bx, by).
double segment_distance(double x, double y, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double t = std::clamp(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
  return std::hypot(x - (ax + t * dx), y - (ay + t * dy));
}

// Common machinery: local-frame SDF and samples, placed by the pose.
class AnalyticSolid : public Solid {
 public:
  double sdf(const Vec3& p) const override {
    return local_sdf(pose.rotation.transpose() * (p - pose.translation));
  }
  SampledSurfels sample(const SampleParams& params) const override {
    require_sample_params(params, area());
    Rng rng(params.seed);
    std::vector<Sample> local;
    local.reserve(static_cast<std::size_t>(1.2 * area() / (params.spacing * params.spacing)) + 16);
    local_samples(params.spacing, params.jitter, rng, local);
    SampledSurfels out;
    const Eigen::Index n = static_cast<Eigen::Index>(local.size());
    out.positions.resize(n, 3);
    out.normals.resize(n, 3);
    out.radii = Values::Constant(n, params.spacing);
    out.part.assign(local.size(), 0);
    for (Eigen::Index i = 0; i < n; ++i) {
      out.positions.row(i) = (pose.rotation * local[i].p + pose.translation).transpose();
      out.normals.row(i) = (pose.rotation * local[i].n).transpose();
    }
    return out;
  }

  virtual double local_sdf(const Vec3& p) const = 0;
  virtual void local_samples(double spacing, double jitter, Rng& rng, std::vector<Sample>& out) const = 0;
};

class Sphere final : public AnalyticSolid {
 public:
  explicit Sphere(double r) : r_(r) {}
  std::string kind() const override { return "sphere"; }
  double area() const override { return 4.0 * kPi * r_ * r_; }
  double local_sdf(const Vec3& p) const override { return p.norm() - r_; }
  void local_samples(double h, double j, Rng& rng, std::vector<Sample>& out) const override {
    sample_arc(0.0, 0.0, r_, 0.0, kPi, 0.0, 2.0 * kPi, Frame{}, h, j, rng, out);
  }

 private:
  double r_;
};

class BoxSolid final : public AnalyticSolid {
 public:
  explicit BoxSolid(const Vec3& e) : e_(e) {}
  std::string kind() const override { return "box"; }
  double area() const override { return 8.0 * (e_.x() * e_.y() + e_.y() * e_.z() + e_.z() * e_.x()); }
  double local_sdf(const Vec3& p) const override {
    const Vec3 q = p.cwiseAbs() - e_;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
  // One regular grid per face, cells of about one spacing; jitter stays inside each cell.
  void local_samples(double h, double j, Rng& rng, std::vector<Sample>& out) const override {
    for (int axis = 0; axis < 3; ++axis) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      const int na = std::max(1, static_cast<int>(std::lround(2.0 * e_[a] / h)));
      const int nb = std::max(1, static_cast<int>(std::lround(2.0 * e_[b] / h)));
      const double da = 2.0 * e_[a] / na, db = 2.0 * e_[b] / nb;
      for (int sign = -1; sign <= 1; sign += 2) {
        Vec3 n = Vec3::Zero();
        n[axis] = sign;
        for (int ia = 0; ia < na; ++ia) {
          for (int ib = 0; ib < nb; ++ib) {
            Vec3 p;
            p[axis] = sign * e_[axis];
            p[a] = -e_[a] + (ia + 0.5 + j * rng.sym()) * da;
            p[b] = -e_[b] + (ib + 0.5 + j * rng.sym()) * db;
            out.push_back({p, n, da * db});
          }
        }
      }
    }
  }

 private:
  Vec3 e_;
};

class Cylinder final : public AnalyticSolid {
 public:
  Cylinder(double r, double hh) : r_(r), hh_(hh) {}
  std::string kind() const override { return "cylinder"; }
  double area() const override { return 2.0 * kPi * r_ * (2.0 * hh_) + 2.0 * kPi * r_ * r_; }
  double local_sdf(const Vec3& p) const override { return rect_sdf(std::hypot(p.x(), p.y()), p.z(), r_, hh_); }
  void local_samples(double h, double j, Rng& rng, std::vector<Sample>& out) const override {
    sample_segment(0.0, hh_, r_, hh_, 0.0, 1.0, Frame{}, h, j, rng, out);     // top cap
    sample_segment(r_, hh_, r_, -hh_, 1.0, 0.0, Frame{}, h, j, rng, out);     // side
    sample_segment(r_, -hh_, 0.0, -hh_, 0.0, -1.0, Frame{}, h, j, rng, out);  // bottom cap
  }

 private:
  double r_, hh_;
};

class Torus final : public AnalyticSolid {
 public:
  Torus(double big, double small) : big_(big), small_(small) {}
  std::string kind() const override { return "torus"; }
  double area() const override { return 4.0 * kPi * kPi * big_ * small_; }
  double local_sdf(const Vec3& p) const override {
    return std::hypot(std::hypot(p.x(), p.y()) - big_, p.z()) - small_;
  }
  void local_samples(double h, double j, Rng& rng, std::vector<Sample>& out) const override {
    sample_arc(big_, 0.0, small_, 0.0, 2.0 * kPi, 0.0, 2.0 * kPi, Frame{}, h, j, rng, out);
  }

 private:
  double big_, small_;
};

class Capsule final : public AnalyticSolid {
 public:
  Capsule(double r, double hl) : r_(r), hl_(hl) {}
  std::string kind() const override { return "capsule"; }
  double area() const override { return 4.0 * kPi * r_ * r_ + 2.0 * kPi * r_ * (2.0 * hl_); }
  double local_sdf(const Vec3& p) const override {
    const double z = std::clamp(p.z(), -hl_, hl_);
    return std::hypot(std::hypot(p.x(), p.y()), p.z() - z) - r_;
  }
  void local_samples(double h, double j, Rng& rng, std::vector<Sample>& out) const override {
    sample_arc(0.0, hl_, r_, 0.0, 0.5 * kPi, 0.0, 2.0 * kPi, Frame{}, h, j, rng, out);
    sample_segment(r_, hl_, r_, -hl_, 1.0, 0.0, Frame{}, h, j, rng, out);
    sample_arc(0.0, -hl_, r_, 0.5 * kPi, kPi, 0.0, 2.0 * kPi, Frame{}, h, j, rng, out);
  }

 private:
  double r_, hl_;
};

// Cup = body (solid of revolution of a U-shaped profile) union handle (half torus).
//
// Body profile in the (rho, z) half-plane, counter-clockwise, outward normals:
//   bottom (0,0)-(R,0) n=(0,-1); outer wall (R,0)-(R,H) n=(1,0); rim (R,H)-(R-w,H) n=(0,1);
//   inner wall (R-w,H)-(R-w,w) n=(-1,0); inner floor (R-w,w)-(0,w) n=(0,1).
// The closing edge on the axis is not surface. Distance to the revolved surface = 2-D distance
// to these five edges (the nearest point lies in the query's own meridian half-plane).
//
// Handle: points within `hr` of the half circle {C + hR (cos u e_x + sin u e_z), u in [-pi/2, pi/2]},
// C = (R, 0, H/2): a half tube with ball caps at its two ends, which sit in the wall.
class Cup final : public AnalyticSolid {
 public:
  Cup(double r, double h, double w, double hR, double hr) : r_(r), h_(h), w_(w), hR_(hR), hr_(hr) {
    // Area of the union surface, integrated once with fine midpoint cells (handle/body overlap removed).
    // Cell size: a sixth of the thinnest feature, but at most ~2e5 cells (the rough area counts
    // the body and the whole half tube).
    const double rough = kPi * r_ * r_ * 2.0 + 2.0 * kPi * r_ * h_ * 2.0 + 2.0 * kPi * kPi * hR_ * hr_;
    const double cell = std::max(std::min(hr_, w_) / 6.0, std::sqrt(rough / 2e5));
    Rng rng(0);
    std::vector<Sample> fine;
    local_samples(cell, 0.0, rng, fine);
    area_ = 0.0;
    for (const Sample& s : fine) area_ += s.area;
  }
  std::string kind() const override { return "cup"; }
  double area() const override { return area_; }

  double body_sdf(const Vec3& p) const {
    const double rho = std::hypot(p.x(), p.y()), z = p.z();
    const double ri = r_ - w_;
    double d = segment_distance(rho, z, 0.0, 0.0, r_, 0.0);
    d = std::min(d, segment_distance(rho, z, r_, 0.0, r_, h_));
    d = std::min(d, segment_distance(rho, z, r_, h_, ri, h_));
    d = std::min(d, segment_distance(rho, z, ri, h_, ri, w_));
    d = std::min(d, segment_distance(rho, z, ri, w_, 0.0, w_));
    const bool inside = z > 0.0 && z < h_ && rho < r_ && !(rho < ri && z > w_);
    return inside ? -d : d;
  }
  double handle_sdf(const Vec3& p) const {
    const double a = p.x() - r_, b = p.z() - 0.5 * h_, c = p.y();
    double dist;
    if (a >= 0.0) {
      dist = std::hypot(std::hypot(a, b) - hR_, c);
    } else {  // nearest arc point is the end on the same side
      dist = std::hypot(a, b - std::copysign(hR_, b), c);
    }
    return dist - hr_;
  }
  double local_sdf(const Vec3& p) const override { return std::min(body_sdf(p), handle_sdf(p)); }

  void local_samples(double h, double j, Rng& rng, std::vector<Sample>& out) const override {
    const double ri = r_ - w_;
    std::vector<Sample> body, handle;
    sample_segment(0.0, 0.0, r_, 0.0, 0.0, -1.0, Frame{}, h, j, rng, body);
    sample_segment(r_, 0.0, r_, h_, 1.0, 0.0, Frame{}, h, j, rng, body);
    sample_segment(r_, h_, ri, h_, 0.0, 1.0, Frame{}, h, j, rng, body);
    sample_segment(ri, h_, ri, w_, -1.0, 0.0, Frame{}, h, j, rng, body);
    sample_segment(ri, w_, 0.0, w_, 0.0, 1.0, Frame{}, h, j, rng, body);
    // Tube: revolve the minor circle about the handle's axis (world -y) over u in [-pi/2, pi/2].
    Frame tube;
    tube.origin = Vec3(r_, 0.0, 0.5 * h_);
    tube.axes.col(0) = Vec3::UnitX();
    tube.axes.col(1) = Vec3::UnitZ();
    tube.axes.col(2) = -Vec3::UnitY();
    sample_arc(hR_, 0.0, hr_, 0.0, 2.0 * kPi, -0.5 * kPi, 0.5 * kPi, tube, h, j, rng, handle);
    // End caps: hemispheres about the arc ends, facing -x (the arc's outgoing tangent there).
    for (int sign = -1; sign <= 1; sign += 2) {
      Frame cap;
      cap.origin = Vec3(r_, 0.0, 0.5 * h_ + sign * hR_);
      cap.axes.col(0) = Vec3::UnitY();
      cap.axes.col(1) = Vec3::UnitZ();
      cap.axes.col(2) = -Vec3::UnitX();
      sample_arc(0.0, 0.0, hr_, 0.0, 0.5 * kPi, 0.0, 2.0 * kPi, cap, h, j, rng, handle);
    }
    for (const Sample& s : body) {
      if (!(handle_sdf(s.p) < 0.0)) out.push_back(s);
    }
    for (const Sample& s : handle) {
      if (!(body_sdf(s.p) < 0.0)) out.push_back(s);
    }
  }

 private:
  double r_, h_, w_, hR_, hr_;
  double area_ = 0.0;
};

template <class T, class... Args>
std::unique_ptr<Solid> place(Pose pose, Args&&... args) {
  require_pose(pose);
  auto solid = std::make_unique<T>(std::forward<Args>(args)...);
  solid->pose = pose;
  return solid;
}

}  // namespace

std::unique_ptr<Solid> make_sphere(double radius, Pose pose) {
  require_positive(radius, "radius");
  return place<Sphere>(pose, radius);
}

std::unique_ptr<Solid> make_box(const Vec3& half_extents, Pose pose) {
  for (int d = 0; d < 3; ++d) {
    if (!std::isfinite(half_extents[d]) || half_extents[d] <= 0.0) {
      throw Error(ErrorCode::InvalidArgument, "half_extents",
                  "component " + std::to_string(d) + " must be finite and > 0, got " + fmt(half_extents[d]));
    }
  }
  return place<BoxSolid>(pose, half_extents);
}

std::unique_ptr<Solid> make_cylinder(double radius, double half_height, Pose pose) {
  require_positive(radius, "radius");
  require_positive(half_height, "half_height");
  return place<Cylinder>(pose, radius, half_height);
}

std::unique_ptr<Solid> make_torus(double major_radius, double minor_radius, Pose pose) {
  require_positive(major_radius, "major_radius");
  require_positive(minor_radius, "minor_radius");
  if (minor_radius >= major_radius) {
    throw Error(ErrorCode::InvalidArgument, "minor_radius",
                "must be < major_radius " + fmt(major_radius) + " (a ring torus), got " + fmt(minor_radius));
  }
  return place<Torus>(pose, major_radius, minor_radius);
}

std::unique_ptr<Solid> make_capsule(double radius, double half_length, Pose pose) {
  require_positive(radius, "radius");
  require_positive(half_length, "half_length");
  return place<Capsule>(pose, radius, half_length);
}

std::unique_ptr<Solid> make_cup(double radius, double height, double wall, double handle_major,
                                double handle_minor, Pose pose) {
  require_positive(radius, "radius");
  require_positive(height, "height");
  require_positive(wall, "wall");
  require_positive(handle_major, "handle_major");
  require_positive(handle_minor, "handle_minor");
  if (wall >= radius) {
    throw Error(ErrorCode::InvalidArgument, "wall", "must be < radius " + fmt(radius) + ", got " + fmt(wall));
  }
  if (wall >= height) {
    throw Error(ErrorCode::InvalidArgument, "wall", "must be < height " + fmt(height) + ", got " + fmt(wall));
  }
  if (handle_minor >= wall) {
    throw Error(ErrorCode::InvalidArgument, "handle_minor",
                "must be < wall " + fmt(wall) + " so the handle's ends sit in the wall, got " + fmt(handle_minor));
  }
  if (handle_minor >= handle_major) {
    throw Error(ErrorCode::InvalidArgument, "handle_minor",
                "must be < handle_major " + fmt(handle_major) + ", got " + fmt(handle_minor));
  }
  if (handle_major + handle_minor >= 0.5 * height) {
    throw Error(ErrorCode::InvalidArgument, "handle_major",
                "handle_major + handle_minor must be < height / 2 = " + fmt(0.5 * height) + ", got " +
                    fmt(handle_major + handle_minor));
  }
  return place<Cup>(pose, radius, height, wall, handle_major, handle_minor);
}

}  // namespace surfeledit
