"""Slow from-scratch references of the four collision algorithms (docs/algorithms.md §4.1-§4.4).

Written independently of the C++ detectors: scipy's cKDTree for nearest neighbours, numpy for the
tests, per-surfel state keyed by surfel id (not by row), and plain Python loops where order
matters (Improved). Conventions (the definitions the session documents):

- inside: ``(p1 - p2) . n2 < W`` with s2 the nearest reference surfel (strict).
- Simple (§4.1): reference = zero region. Boundary marks at reset: for every deformable surfel its
  ``n`` nearest other surfels of the whole model; the ``i`` nearest zero surfels among them are
  marked. Step bound: with t the surfel's own displacement this step, if
  ``|d|^2 > (|t| + r1 + r2)^2`` the surfel keeps its previous state; else it collides iff inside
  and its nearest zero surfel is not marked (boundary heuristic on).
- Improved (§4.2): Simple's test in ascending id order; after testing s1 with ``|d|^2 > H`` every
  deformable surfel not yet settled this step lying strictly inside ``B(p1, |d|)`` takes s1's
  state untested. H = mean ``|d|^2`` of the previous step's tested surfels, 0 on the first step.
- Temporal (§4.3): sphere (c, rho^2) per deformable surfel, initially its position and squared
  distance to the nearest zero surfel; strictly inside (``|p - c|^2 < rho^2``) -> skip; else
  re-centre on the nearest zero surfel and test as Simple.
- Robust (§4.4, Code 6.8): against the original whole model, parity of counted inside changes,
  first-update re-evaluation at the old position, old position kept while not colliding.
- Dynamic resampling: an inserted surfel (child B) has a parent (whose row became child A). B takes
  the parent's state (Simple/Improved: colliding; Robust: inside, colliding, first update, old
  position) and the parent's displacement base (previous position); B takes the parent's sphere if
  it lies strictly inside it, else an empty sphere at its position; A keeps the sphere only if it
  lies strictly inside it, else gets an empty one.
- Removal: the state of removed surfels is dropped; a removed zero surfel leaves the reference set
  (Robust: the original model; removed deformable surfels stay in the original model).
"""

from __future__ import annotations

from typing import Dict, Iterable, Mapping, Optional

import numpy as np
from scipy.spatial import cKDTree

from surfeledit.scenario import ModelState
from surfeledit.scenes import SceneSetup


class Reference:
    """Base: rest model, per-id arrays that grow with inserted ids, state bookkeeping."""

    def __init__(self, scene: SceneSetup, threshold: float = 0.0, boundary: bool = True, boundary_n: int = 10,
                 boundary_i: int = 5, step_bound: bool = True, sphere_margin: float = 0.5) -> None:
        self.W = float(threshold)
        self.margin = float(sphere_margin)
        self.boundary = boundary
        self.n, self.i = int(boundary_n), int(boundary_i)
        self.step_bound = step_bound
        P = scene.size
        self.rest_pos = scene.positions.copy()
        self.rest_nrm = scene.normals.copy()
        self.rest_rad = scene.radii.copy()
        self.is_zero_rest = np.zeros(P, bool)
        self.is_zero_rest[scene.zero] = True
        self.zero_alive = self.is_zero_rest.copy()  # zero surfels not removed
        self.alive = np.ones(P, bool)               # per id
        self.prev = self.rest_pos.copy()            # per id: position after the last step
        self._build_zero()

    # -- per-id arrays -------------------------------------------------------------------------
    def _grow(self, size: int) -> None:
        old = self.alive.shape[0]
        if size <= old:
            return
        for name in self._per_id():
            a = getattr(self, name)
            shape = (size,) + a.shape[1:]
            b = np.zeros(shape, a.dtype)
            b[:old] = a
            setattr(self, name, b)

    def _per_id(self) -> Iterable[str]:
        return ("alive", "prev", "is_zero_rest", "zero_alive")

    def _build_zero(self) -> None:
        self.zero_ids = np.flatnonzero(self.zero_alive[: self.rest_pos.shape[0]])
        self.zero_tree = cKDTree(self.rest_pos[self.zero_ids])

    def sphere_rho2(self, d: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """Sphere radius^2 of the definition: (|d| - sphere_margin * r2)^2, 0 when not positive."""
        dist2 = np.einsum("ij,ij->i", d, d)
        if self.margin == 0.0:
            return dist2
        rho = np.sqrt(dist2) - self.margin * radius
        return np.where(rho > 0.0, rho * rho, 0.0)

    def nearest_zero(self, p: np.ndarray):
        _, k = self.zero_tree.query(p, k=1)
        z = self.zero_ids[k]
        return z, p - self.rest_pos[z], self.rest_nrm[z]

    # -- events --------------------------------------------------------------------------------
    def remove(self, ids: Iterable[int]) -> None:
        ids = np.asarray(list(ids), np.int64)
        self.alive[ids] = False
        if self.zero_alive[ids].any():
            self.zero_alive[ids] = False
            self._build_zero()

    def insert(self, parents: Mapping[int, int], state: ModelState) -> None:
        """New ids (child B) with their parent ids; ``state`` is the model after the split."""
        if not parents:
            return
        self._grow(int(max(parents)) + 1)
        pos = dict(zip(state.ids.astype(np.int64).tolist(), state.positions))
        for b, a in sorted(parents.items()):
            self.alive[b] = True
            self.prev[b] = self.prev[a]
            self._inherit(b, a, pos[b])
        for a in sorted(set(parents.values())):
            self._child_a(a, pos[a])

    def _inherit(self, b: int, a: int, pb: np.ndarray) -> None:
        raise NotImplementedError

    def _child_a(self, a: int, pa: np.ndarray) -> None:
        pass

    # -- a step --------------------------------------------------------------------------------
    def step(self, state: ModelState, parents: Optional[Mapping[int, int]] = None) -> np.ndarray:
        """Evaluates the model after one step; returns the colliding ids, ascending (uint64)."""
        if parents:
            self.insert(parents, state)
        ids = state.ids.astype(np.int64)
        assert np.all(self.alive[ids]), "the model holds ids the reference believes removed"
        assert int(np.count_nonzero(self.alive)) == len(ids), "the model lost ids the reference still holds"
        order = np.argsort(ids)
        ids, pos, rad = ids[order], state.positions[order], state.radii[order]
        d = ~self.is_zero_rest[ids]
        out = self._detect(ids[d], pos[d], rad[d])
        self.prev[ids] = pos
        return np.sort(out).astype(np.uint64)

    def _detect(self, ids: np.ndarray, pos: np.ndarray, rad: np.ndarray) -> np.ndarray:
        raise NotImplementedError


class SimpleRef(Reference):
    """§4.1 (and, with ``improved=True``, §4.2)."""

    def __init__(self, scene: SceneSetup, improved: bool = False, **kw) -> None:
        super().__init__(scene, **kw)
        self.improved = improved
        self.colliding = np.zeros(scene.size, bool)
        self.marked = np.zeros(scene.size, bool)
        self.H = 0.0
        if self.boundary:
            whole = cKDTree(self.rest_pos)
            dids = np.flatnonzero(~self.is_zero_rest)
            _, nb = whole.query(self.rest_pos[dids], k=self.n + 1)
            for row, s in zip(nb, dids):
                others = [j for j in row if j != s][: self.n]
                zeros = [j for j in others if self.is_zero_rest[j]][: self.i]
                self.marked[zeros] = True

    def _per_id(self):
        return tuple(super()._per_id()) + ("colliding", "marked")

    def _inherit(self, b, a, pb):
        self.colliding[b] = self.colliding[a]

    def _test(self, ids, pos, rad):
        """Vectorised §4.1 test: (new state, |d|^2)."""
        z, d, n2 = self.nearest_zero(pos)
        dist2 = np.einsum("ij,ij->i", d, d)
        state = (np.einsum("ij,ij->i", d, n2) < self.W)
        if self.boundary:
            state &= ~self.marked[z]
        if self.step_bound:
            t = np.linalg.norm(pos - self.prev[ids], axis=1)
            bound = t + rad + self.rest_rad[z]
            far = dist2 > bound * bound
            state = np.where(far, self.colliding[ids], state)
        return state, dist2

    def _detect(self, ids, pos, rad):
        state, dist2 = self._test(ids, pos, rad)
        if not self.improved:
            self.colliding[ids] = state
            return ids[state]
        # Improved: ascending id order, each tested ball settles the untested surfels strictly in it.
        tree = cKDTree(pos)
        settled = np.zeros(len(ids), bool)
        total, tested = 0.0, 0
        for q in range(len(ids)):
            if settled[q]:
                continue
            settled[q] = True
            self.colliding[ids[q]] = state[q]
            total += dist2[q]
            tested += 1
            if not dist2[q] > self.H:
                continue
            reach = float(np.sqrt(dist2[q]))
            for j in tree.query_ball_point(pos[q], reach * 1.001 + 1e-12):
                if settled[j]:
                    continue
                e = pos[j] - pos[q]
                if float(e @ e) < dist2[q]:
                    settled[j] = True
                    self.colliding[ids[j]] = state[q]
        self.H = total / tested if tested else 0.0
        self.last_tested = tested
        return ids[self.colliding[ids]]


def _split_sphere_child_b(ref, b, a, pb):
    """§4.4 split rule (docs/algorithms.md): child b takes parent a's sphere when it lies inside it, else an empty one."""
    e = pb - ref.center[a]
    if float(e @ e) < ref.rho2[a]:
        ref.center[b], ref.rho2[b] = ref.center[a], ref.rho2[a]
    else:
        ref.center[b], ref.rho2[b] = pb, 0.0


def _split_sphere_child_a(ref, a, pa):
    """§4.4 split rule: the parent row (child a) keeps its sphere only while it still lies inside it."""
    e = pa - ref.center[a]
    if not float(e @ e) < ref.rho2[a]:
        ref.center[a], ref.rho2[a] = pa, 0.0


class TemporalRef(SimpleRef):
    """§4.3: Simple with spheres."""

    def __init__(self, scene: SceneSetup, **kw) -> None:
        super().__init__(scene, improved=False, **kw)
        self.center = self.rest_pos.copy()
        self.rho2 = np.zeros(scene.size)
        dids = np.flatnonzero(~self.is_zero_rest)
        z, d, _ = self.nearest_zero(self.rest_pos[dids])
        self.rho2[dids] = self.sphere_rho2(d, self.rest_rad[z])

    def _per_id(self):
        return tuple(super()._per_id()) + ("center", "rho2")

    def _inherit(self, b, a, pb):
        super()._inherit(b, a, pb)
        _split_sphere_child_b(self, b, a, pb)

    def _child_a(self, a, pa):
        _split_sphere_child_a(self, a, pa)

    def _detect(self, ids, pos, rad):
        e = pos - self.center[ids]
        out = ~(np.einsum("ij,ij->i", e, e) < self.rho2[ids])
        self.last_tested = int(out.sum())
        if out.any():
            state, dist2 = self._test(ids[out], pos[out], rad[out])
            z, d, _ = self.nearest_zero(pos[out])
            self.colliding[ids[out]] = state
            self.center[ids[out]] = pos[out]
            self.rho2[ids[out]] = self.sphere_rho2(d, self.rest_rad[z])
        return ids[self.colliding[ids]]


class RobustRef(Reference):
    """§4.4, Code 6.8."""

    def __init__(self, scene: SceneSetup, **kw) -> None:
        super().__init__(scene, **kw)
        P = scene.size
        self.inside = np.zeros(P, bool)
        self.colliding = np.zeros(P, bool)
        self.first = np.ones(P, bool)
        self.old = self.rest_pos.copy()
        self.center = self.rest_pos.copy()
        self.rho2 = np.zeros(P)
        dids = np.flatnonzero(~self.is_zero_rest)
        z, d, _ = self.nearest_zero(self.rest_pos[dids])
        self.rho2[dids] = self.sphere_rho2(d, self.rest_rad[z])
        self.orig_alive = np.ones(P, bool)  # rows of the original model still in it
        self._build_orig()

    def _per_id(self):
        return tuple(super()._per_id()) + ("inside", "colliding", "first", "old", "center", "rho2")

    def _build_orig(self) -> None:
        self.orig_ids = np.flatnonzero(self.orig_alive)
        self.orig_tree = cKDTree(self.rest_pos[self.orig_ids])

    def remove(self, ids):
        ids = np.asarray(list(ids), np.int64)
        super().remove(ids)
        gone = ids[(ids < self.orig_alive.shape[0]) & self.is_zero_rest[ids]]
        if len(gone):
            self.orig_alive[gone] = False
            self._build_orig()

    def _classify(self, p):
        _, k = self.orig_tree.query(p, k=1)
        o = self.orig_ids[k]
        d = p - self.rest_pos[o]
        return o, d, np.einsum("ij,ij->i", d, self.rest_nrm[o]) < self.W

    def _inherit(self, b, a, pb):
        for name in ("inside", "colliding", "first", "old"):
            getattr(self, name)[b] = getattr(self, name)[a]
        _split_sphere_child_b(self, b, a, pb)

    def _child_a(self, a, pa):
        _split_sphere_child_a(self, a, pa)

    def _detect(self, ids, pos, rad):
        e = pos - self.center[ids]
        left = np.einsum("ij,ij->i", e, e) >= self.rho2[ids]
        self.last_tested = int(left.sum())
        lid, lpos = ids[left], pos[left]
        first = self.first[lid]
        if first.any():
            _, _, was_in = self._classify(self.old[lid[first]])
            self.inside[lid[first]] = was_in
            self.first[lid[first]] = False
        o, d, now_in = self._classify(lpos)
        self.center[lid] = lpos
        self.rho2[lid] = self.sphere_rho2(d, self.rest_rad[o])
        flip = self.is_zero_rest[o] & (now_in != self.inside[lid])
        self.colliding[lid[flip]] = ~self.colliding[lid[flip]]
        self.inside[lid] = now_in
        free = ~self.colliding[ids]
        self.old[ids[free]] = pos[free]
        return ids[self.colliding[ids]]


def make_reference(algorithm: str, scene: SceneSetup, **settings) -> Reference:
    kw = {k: v for k, v in settings.items()
          if k in ("threshold", "boundary", "boundary_n", "boundary_i", "step_bound", "sphere_margin")}
    if algorithm == "simple":
        return SimpleRef(scene, improved=False, **kw)
    if algorithm == "improved":
        return SimpleRef(scene, improved=True, **kw)
    if algorithm == "temporal":
        return TemporalRef(scene, **kw)
    if algorithm == "robust":
        return RobustRef(scene, **{k: v for k, v in kw.items() if k in ("threshold", "sphere_margin")})
    raise ValueError(algorithm)


def split_parents(inserted: np.ndarray, state: ModelState) -> Dict[int, int]:
    """Parent id of each inserted id (child B): the one other surfel with a bit-identical normal and
    radius (a split copies the normal and gives both children the same radius). Asserts uniqueness."""
    if len(inserted) == 0:
        return {}
    ids = state.ids.astype(np.int64)
    key = {}
    for i, n, r in zip(ids.tolist(), state.normals, state.radii):
        key.setdefault((n.tobytes(), float(r)), []).append(i)
    new = set(int(x) for x in inserted)
    out: Dict[int, int] = {}
    pos = dict(zip(ids.tolist(), state.positions))
    for b in sorted(new):
        row = int(np.flatnonzero(ids == b)[0])
        cands = [i for i in key[(state.normals[row].tobytes(), float(state.radii[row]))] if i != b and i not in new]
        assert len(cands) == 1, f"inserted id {b}: {len(cands)} parent candidates"
        out[b] = cands[0]
        assert np.linalg.norm(pos[b] - pos[cands[0]]) < 4 * float(state.radii[row]) + 1e-12
    return out
