// EditSession's response to a colliding step (docs/algorithms.md §7, thesis ch. 11): report, cancel
// (§7 b) or back-off (§7 c). Every re-application starts from the step's before-image, so the result
// is the state a single step of the kept fraction would have produced, deterministically.
#include <algorithm>
#include <chrono>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

double largest(const std::vector<double>& depths) {
  return depths.empty() ? 0.0 : *std::max_element(depths.begin(), depths.end());
}

// Largest displacement of a deformable row between `before` and `now` (#P by 3 each over `rows`).
double largest_move(const RowsImage& before, const Points& now) {
  double d2 = 0.0;
  for (std::size_t k = 0; k < before.rows.size(); ++k)
    d2 = std::max(d2, (now.row(before.rows[k]) - before.positions.row(static_cast<Eigen::Index>(k))).squaredNorm());
  return std::sqrt(d2);
}

}  // namespace

void EditSession::respond(const DeformParams& params, const SessionImage& before, std::uint64_t version_before,
                          StepResult& out) {
  if (!out.detected || out.colliding.empty()) return;  // response "none"
  const ResponseParams& rp = settings_.response;
  if (rp.mode == Response::Report) {
    out.response = "reported";
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  // Back to the state before the step (a fresh clone of a whole image's detector: the image is reused).
  auto take_back = [&] {
    restore(before, true);
    version_ = version_before;
  };
  if (rp.mode == Response::Cancel) {
    // The reply keeps the ids that would have collided; the session is exactly as before the step.
    take_back();
    out.response = "cancelled";
    out.response_ms = ms_since(start);
    return;
  }
  // Back-off (§7 c). Translation alone: the thesis's iteration -- the deepest surfel (scale factor s
  // = beta(lambda)) retreats by its real translation length depth / s along -t. With rotation:
  // bisection of the step fraction until the bracket is narrower than epsilon in displacement.
  const double eps = rp.backoff_epsilon > 0.0 ? rp.backoff_epsilon : 1e-3 * model_.radii().mean();
  const bool rotation = params.angle != 0.0;
  const double t_len = params.translation.norm();
  // Largest displacement of the full step (rotation: the bracket's width in model units).
  const double full_move = before.rows ? largest_move(*before.rows, model_.positions()) : t_len;
  DeformParams p = params;
  p.center = out.center;  // the centre of the full step, for every fraction
  double depth = largest(out.depths);
  double kept = 1.0, lo = 0.0, hi = 1.0;  // rotation: lo never collided, hi collides
  int iterations = 0;
  auto apply = [&](double f) {
    take_back();
    p.translation = params.translation * f;
    p.angle = params.angle * f;
    step_once(p, out);
    depth = largest(out.depths);
    ++iterations;
  };
  while (iterations < rp.backoff_max_iterations) {
    if (!rotation) {
      if (depth < eps || out.colliding.empty()) break;
      const auto deepest = std::max_element(out.depths.begin(), out.depths.end()) - out.depths.begin();
      const Index row = model_.row_of(out.colliding[static_cast<std::size_t>(deepest)]);
      const double s = blend_value(params.blend, fields_->lambda[row]);
      if (s <= 0.0 || t_len <= 0.0) break;
      kept = std::max(0.0, kept - depth / (s * t_len));
      apply(kept);
    } else {
      if (out.colliding.empty()) lo = kept;
      else if (depth < eps) break;
      else hi = kept;
      if ((hi - lo) * full_move < eps) break;
      kept = 0.5 * (lo + hi);
      apply(kept);
    }
  }
  // Bisection ends on the last fraction that did not collide when the last one tried still did.
  if (rotation && !out.colliding.empty() && depth >= eps && kept != lo) {
    kept = lo;
    apply(kept);
  }
  out.response = "backed_off";
  out.backoff = {iterations, kept, depth};
  out.response_ms = ms_since(start);
}

}  // namespace surfeledit
