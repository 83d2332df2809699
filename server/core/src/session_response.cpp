// EditSession's response to a colliding step (docs/algorithms.md §7, thesis ch. 11): report, cancel
// (§7 b), back-off (§7 c) or merge (§7 d, session_merge.cpp). Every re-application starts from the step's before-image, so the result
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
  const IndexList& rows = *before.rows;
  for (std::size_t k = 0; k < rows.size(); ++k)
    d2 = std::max(d2, (now.row(rows[k]) - before.positions.row(static_cast<Eigen::Index>(k))).squaredNorm());
  return std::sqrt(d2);
}

}  // namespace

void EditSession::respond(const DeformParams& params, SessionImage& before, std::uint64_t version_before,
                          StepResult& out) {
  if (!out.detected || out.colliding.empty()) return;  // response "none"
  const ResponseParams& rp = tool_->settings.response;
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
  if (rp.mode == Response::Merge) {
    // The step is kept; `colliding` keeps the ids that collided (the merge removed them). The rows
    // moved are renumbered: `moved` becomes every row changed by the step or the merge.
    // The history needs the whole session before the step: built now (a merge is rare), from the rows
    // image; the detector after the step is replaced by the merge and becomes the image's once its
    // states before the step are back. A refused merge takes the step back.
    SessionImage whole = before.rows ? whole_before_step(before) : SessionImage();
    const std::shared_ptr<const DetectorImage> states = before.rows && tool_->detector ? step_detector_image(before) : nullptr;
    MergeOutcome m;
    try {
      m = merge_now(true);
    } catch (...) {
      take_back();
      throw;
    }
    if (before.rows) {
      const std::shared_ptr<CollisionDetector>& d = whole.whole->tools.at(whole.tool).detector;
      if (states) d->restore_image(*states);
      if (d) d->stop_journal();
      before = std::move(whole);
    }
    out.features = m.features;
    out.inserted.insert(out.inserted.end(), m.inserted.begin(), m.inserted.end());
    out.moved = model_.rows_of(changes_since(version_before).changed, "changed");
    out.response = "merged";
    out.response_ms = ms_since(start);
    return;
  }
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
  // Iterations re-test only the surfels that collided after the full step (or before it); one full
  // detection of the kept fraction ends the response, so the result is exactly a step of that fraction.
  std::vector<std::uint8_t> candidate(static_cast<std::size_t>(model_.size()), 0);
  const IdList& collided = out.colliding;
  for (const IdList* ids : {&collided, static_cast<const IdList*>(&before.colliding)})  // those colliding before keep that state otherwise
    for (SurfelId id : *ids) candidate[static_cast<std::size_t>(model_.row_of(id))] = 1;
  const bool partial = before.rows.has_value();  // resampling (whole images) may add rows: full re-tests
  double depth = largest(out.depths);
  double kept = 1.0, lo = 0.0, hi = 1.0;  // rotation: lo never collided, hi collides
  int iterations = 0;
  double applied = 1.0;  // the fraction the whole state holds now
  // A full step of fraction f from the state before the step.
  auto apply = [&](double f) {
    take_back();
    applied = f;
    p.translation = params.translation * f;
    p.angle = params.angle * f;
    step_once(p, out);
    depth = largest(out.depths);
  };
  // Re-tests of the candidates alone: their rows and detector states before the step (`small`), the
  // positions before it (`previous`); only they move (fraction f) and are tested.
  IndexList rows;
  SessionImage small;
  const Points& previous = tool_->previous;  // step_once() left the positions before the step there
  auto prepare = [&] {
    take_back();
    applied = 0.0;
    rows.clear();
    for (Index r : tool_->fields->deformable)
      if (candidate[static_cast<std::size_t>(r)]) rows.push_back(r);
    small = capture_rows(rows, true);
  };
  auto retest = [&](double f) {
    if (!partial) return apply(f);
    restore(small, false);
    p.translation = params.translation * f;
    p.angle = params.angle * f;
    SurfelArrays& a = model_.arrays();
    const bool tangents = model_.has_tangents();
    apply_step(*tool_->fields, p, a.positions, a.normals, tangents ? &a.tangent_u : nullptr,
               tangents ? &a.tangent_v : nullptr, 1, &rows);  // only the candidates move
  };
  auto detect_candidates = [&] {
    if (!partial) return;
    const CollisionResult c = tool_->detector->detect_only(
        CollisionScene{model_.positions(), model_.normals(), model_.radii(), tool_->fields->regions}, previous, candidate);
    out.colliding.clear();
    for (Index r : c.colliding) out.colliding.push_back(model_.id_of(r));
    out.depths = c.depths;
    depth = largest(out.depths);
  };
  // One round of re-tests from the current result (`out`, at fraction `kept`).
  auto round = [&] {
    while (iterations < rp.backoff_max_iterations) {
      if (!rotation) {
        if (depth < eps || out.colliding.empty()) return;
        const auto deepest = std::max_element(out.depths.begin(), out.depths.end()) - out.depths.begin();
        const Index row = model_.row_of(out.colliding[static_cast<std::size_t>(deepest)]);
        const double s = blend_value(params.blend, tool_->fields->lambda_of(row));
        if (s <= 0.0 || t_len <= 0.0) return;
        kept = std::max(0.0, kept - depth / (s * t_len));
      } else {
        if (out.colliding.empty()) lo = kept;
        else if (depth < eps) return;
        else hi = kept;
        if ((hi - lo) * full_move < eps) break;
        kept = 0.5 * (lo + hi);
      }
      retest(kept);
      detect_candidates();
      ++iterations;
    }
    // Bisection ends on the last fraction that did not collide when the last one tried still did.
    if (rotation && !out.colliding.empty() && depth >= eps) kept = lo;
  };
  // Translation with a journal: the kept fraction is applied to every row, and the detector re-tests the
  // candidates and the rows its detection of the whole step re-evaluated with a query. Every other row
  // stayed inside its empty sphere over the whole step, so over any part of it too (a segment inside a
  // ball): its state is that of before the step, as a step of the kept fraction would leave it.
  std::vector<std::uint8_t> final_rows;
  const bool quick = partial && !rotation &&
                     (final_rows = candidate, tool_->detector->journal_tested(final_rows));
  auto finish = [&](double f) {
    take_back();
    applied = f;
    p.translation = params.translation * f;
    p.angle = 0.0;
    SurfelArrays& a = model_.arrays();
    const bool tangents = model_.has_tangents();
    const DeformResult r = apply_step(*tool_->fields, p, a.positions, a.normals, tangents ? &a.tangent_u : nullptr,
                                      tangents ? &a.tangent_v : nullptr, params_.threads);
    ++version_;
    touch_rows(r.moved);
    out.seq = ++tool_->steps;
    out.moved = r.moved;
    const CollisionResult c = tool_->detector->detect_only(
        CollisionScene{model_.positions(), model_.normals(), model_.radii(), tool_->fields->regions}, previous, final_rows);
    out.colliding.clear();
    for (Index row : c.colliding) out.colliding.push_back(model_.id_of(row));
    out.depths = c.depths;
    out.stats = c.stats;
    tool_->colliding = out.colliding;
    depth = largest(out.depths);
  };
  // Re-testing only the candidates can miss a surfel that did not collide after the whole step but does
  // after part of it (e.g. one that crossed a thin zero part): the detection of the kept fraction then
  // finds it, and it joins the candidates for another round.
  for (;;) {
    if (partial) prepare();
    round();
    if (iterations == 0 && partial) {  // nothing re-tested: back to the whole step as it was
      apply(1.0);
      break;
    }
    if (iterations == 0 || (!partial && applied == kept)) break;
    if (quick) finish(kept);
    else apply(kept);
    bool grew = false;
    for (SurfelId id : out.colliding) {
      std::uint8_t& c = candidate[static_cast<std::size_t>(model_.row_of(id))];
      grew |= c == 0;
      c = 1;
    }
    const bool settled = out.colliding.empty() || depth < eps;
    if (!partial || settled || !grew || iterations >= rp.backoff_max_iterations) break;
    if (rotation) lo = 0.0;  // `kept` collides after all: only the state before the step is known clear
  }
  out.response = "backed_off";
  out.backoff = {iterations, kept, depth};
  out.response_ms = ms_since(start);
}

}  // namespace surfeledit
