// Scripted ops of two authors, "a" and "b", on the two-arms scene (two_arms.hpp): steps that move their arms
// towards each other, per-author undo and redo, and (optionally) configures. The session snapshot tests
// replay one script on sessions that must agree.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "surfeledit/core/deformation.hpp"

namespace surfeledit::test {

struct ScriptOp {
  enum Kind { Step = 0, Undo = 1, Redo = 2, Configure = 3 };
  Kind kind = Step;
  std::string author;         // "a" or "b"
  Vec3 t = Vec3::Zero();      // a step's translation (model units)
  double angle = 0.0;         // a step's rotation about +y (radians)
};

// How many of every `total` draws are steps, undos and redos (the rest configures).
struct OpMix {
  std::uint32_t steps = 6, undos = 2, redos = 2, total = 10;
};

// `n` ops from `seed`. Arm A moves towards +x, arm B towards -x: they meet after a few steps each.
inline std::vector<ScriptOp> two_author_script(std::uint32_t seed, int n, OpMix mix = {}) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<ScriptOp> ops;
  for (int k = 0; k < n; ++k) {
    ScriptOp op;
    op.author = rng() % 2 ? "a" : "b";
    const std::uint32_t r = rng() % mix.total;
    op.kind = r < mix.steps                         ? ScriptOp::Step
              : r < mix.steps + mix.undos             ? ScriptOp::Undo
              : r < mix.steps + mix.undos + mix.redos ? ScriptOp::Redo
                                                      : ScriptOp::Configure;
    const double dir = op.author == "a" ? 1.0 : -1.0;
    op.t = Vec3(dir * (0.04 + 0.02 * u(rng)), 0.01 * u(rng), 0.01 * u(rng));
    op.angle = 0.05 * u(rng);
    ops.push_back(op);
  }
  return ops;
}

// The deformation of a step op.
inline DeformParams step_params(const ScriptOp& op) {
  DeformParams p;
  p.translation = op.t;
  p.axis = Vec3::UnitY();
  p.angle = op.angle;
  return p;
}

}  // namespace surfeledit::test
