// The oriented particle engine (thesis §12): particles, the rigid region they blend into, and one iteration
// at a time (forces, stable-step check, integration, projection, local adaptive split / kill).
#pragma once

#include <functional>
#include <memory>

#include "surfeledit/core/particles/forces.hpp"
#include "surfeledit/core/particles/projection.hpp"
#include "surfeledit/core/particles/verlet.hpp"

namespace surfeledit {

// s_i = (d_i / max_k d_k)^gamma, d_i the distance of particle i to the nearest rigid point (Eq. 12.28).
// `particles` #P by 3, `rigid` #R by 3; all 1 when #R = 0, all 0 when every d_i is 0.
Values region_scale(const Points& particles, const Points& rigid, double gamma);

struct StepReport {
  double energy = 0.0;     // sum of the potentials before the step
  double dt_stable = 0.0;  // stable time step at the start of the step
  int substeps = 1;        // sub-steps the iteration took
  Index split = 0;         // particles added by local adaptive repulsion
  Index killed = 0;        // particles removed
};

class ParticleEngine {
 public:
  // Throws InvalidArgument on bad params or input (non-finite, inconsistent sizes).
  ParticleEngine(ParticleState state, const Points& rigid, ParticleParams params);

  // The original surface for project_tangent and project_mls: #S by 3 positions and unit normals.
  void set_surface(const Points& positions, const Points& normals);

  // A surface the particles are kept on instead of the tangent planes: after every move, each particle's
  // position x becomes constraint(x, &n) and its normal n (unit) when the function sets it.
  using Constraint = std::function<Vec3(const Vec3& x, Vec3* normal)>;
  void set_constraint(Constraint constraint);

  // One iteration of params.dt (sub-stepped, or refused with Conflict("dt"), above the stable step).
  StepReport step();
  // Moves every particle onto the MLS surface of the original samples (kernel width h) and sets its normal.
  void project_mls(double h);

  const ParticleState& state() const { return state_; }
  const Values& scale() const { return scale_; }
  const Neighbourhood& neighbourhood() const { return nbrs_; }
  const ParticleParams& params() const { return params_; }
  double energy();          // at the current state
  double stable_dt();       // at the current state

 private:
  void refresh_neighbours(bool force);
  void evaluate();
  void project_tangent();
  void apply_constraint();
  void adapt(StepReport& report);

  ParticleState state_;
  Points rigid_;
  ParticleParams params_;
  Values scale_;
  Neighbourhood nbrs_;
  GridWorkspace grid_;  // the grid builder's buffers (cached neighbourhoods)
  VerletList verlet_;   // recomputed grid neighbourhoods
  SystemForces forces_;
  bool evaluated_ = false;
  std::unique_ptr<SurfaceProjector> surface_;
  Constraint constraint_;
};

}  // namespace surfeledit
