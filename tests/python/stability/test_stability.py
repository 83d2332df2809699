"""The stability matrix (surfeledit.stability, issue 13 §3) in CI: every row under every condition,
the long session bounded to 2,000 steps (``python -m surfeledit.stability`` runs 100,000).

Reference: the same scene untouched (translations, scales, float32), the exact truth of the scene's
signed distance (huge steps), the first steps of the same pose (long sessions). The tolerances are the
module's constants and are stated in the README's "Precision" section."""

import math

from surfeledit import stability as M

# Cells that fail by design, with the bound the README states: after a step of 10x the model size the
# blended part is stretched through the slab, and the thesis's nearest-surfel tests (boundary marks,
# step bound) miss up to ~41% of the true collisions; inside = winding | vote get it right.
KNOWN = {(row, "huge") for row in ("simple", "improved", "temporal/nearest", "temporal+simplify")}


def test_every_condition_within_tolerance_and_known_failures_finite():
    """One test over the whole matrix (~24 s), so that it is computed once whichever pytest-xdist worker runs it
    (a fixture is computed again by every worker that draws a test using it, and by a worker that switched modules)."""
    rows, columns = list(M.ALGORITHMS), list(M.CONDITIONS)
    matrix = M.matrix(rows, columns, long_steps=2000)
    print("\n" + M.format_table(matrix, rows, columns))
    failed = [f"{row} / {c}: {matrix[row, c][0]}" for row in rows for c in columns
              if not matrix[row, c][1] and (row, c) not in KNOWN]
    assert not failed, failed
    for row, col in KNOWN:
        text, _ = matrix[row, col]
        assert text.endswith("wrong"), text  # a measured fraction, not NaN or a crash
        assert math.isfinite(float(text.split()[0])) and float(text.split()[0]) < 0.5


def test_the_deviation_cells_measure_something():
    """Two sessions are compared, not one with itself: a run whose one region moved half a spacing
    more fails the position tolerance (the check can fail)."""
    scene = M._scenes.concave(scale=M.SCALE, steps=M.STEPS)
    ref = M.Run(scene, M.ALGORITHMS["robust/nearest"]).motion()
    other = M.Run(scene, M.ALGORITHMS["robust/nearest"]).motion()
    other.step(translation=(0.0, 0.0, 0.5 * scene.spacing))
    try:
        assert M._deviation(other.positions(), ref.positions()) / scene.spacing > 0.4 > M.POS_TOL
    finally:
        ref.close()
        other.close()
