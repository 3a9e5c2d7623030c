"""The monotone allocator (evotol/allocators/monotone.py, issue 43 "monotone on a per-axis problem: seconds").

1. **One cut**: the dominance of the new vertices decided from the pairs of vertices above the cut point
   (:func:`_cut`) against comparing each new vertex with every vertex (the definition), on the same polyblocks;
   per dimension the vertices, both times, their ratio and whether the vertices kept are the same. The
   polyblocks are built by cutting the unit box at random points z (seeded) below a vertex until they have at
   least 300 vertices, as the search does on a 36-source problem in its first rounds.
2. **The whole allocator at its default budget** on the UR5 study's 36 sources (reports/studies/ur5_urdf.toml,
   27 poses): wall time, what stopped it and its bracket.

    python benchmarks/bench_polyblock.py
"""
from __future__ import annotations

import time
import tomllib
from pathlib import Path

import numpy as np

from evotol.allocators.monotone import _cut, new_vertices


def cut_every_pair(V: np.ndarray, z: np.ndarray, chunk: int = 256) -> np.ndarray:
    """The cut with each new vertex compared with every vertex (the definition of dominance)."""
    split = new_vertices(V, z)
    if split is None:
        return V
    keep, cand = split
    allv = np.concatenate([keep, cand])
    ok = np.ones(len(cand), bool)
    for s in range(0, len(cand), chunk):
        c = cand[s:s + chunk]
        ge = np.all(allv[None, :, :] >= c[:, None, :], axis=2)
        eq = np.all(allv[None, :, :] == c[:, None, :], axis=2)
        ok[s:s + chunk] = ~np.any(ge & ~eq, axis=1)
    return np.concatenate([keep, cand[ok]])


def polyblock_of(n: int, size: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """A polyblock of about ``size`` vertices in ``n`` dimensions and the next cut point below one of its vertices."""
    V = np.ones((1, n))
    while True:
        v = V[rng.integers(len(V))]
        z = v * rng.uniform(0.6, 0.99, n)
        if len(V) >= size:
            return V, z
        V = _cut(V, z)


def whole_allocator() -> None:
    """``allocate_monotone`` at its default budget on the UR5 study's problem (36 sources)."""
    from evotol.allocators import allocate_monotone
    from evotol.studyfile import load_problem
    path = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ur5_urdf.toml"
    problem = load_problem(tomllib.loads(path.read_text()), base_dir=path.parent)
    t0 = time.perf_counter()
    res = allocate_monotone(problem)
    c = res.certificate
    print(f"monotone allocator, UR5 study ({len(problem.names)} sources, {len(problem.poses)} poses), default budget: "
          f"{time.perf_counter() - t0:.1f} s wall ({c['evaluations']} evaluations, {c['vertices']} vertices, "
          f"{c['rounds']} rounds; bracket [{c['lower_bound']:.4g}, {res.cost:.4g}], gap {c['gap']:.3f})")


def main() -> None:
    rng = np.random.default_rng(0)
    print("polyblock cut (monotone allocator): pairs above the cut vs every pair, one cut, same polyblock")
    for n in (12, 24, 36):
        V, z = polyblock_of(n, 300, rng)
        t0 = time.perf_counter()
        new = _cut(V, z)
        t_new = time.perf_counter() - t0
        t0 = time.perf_counter()
        old = cut_every_pair(V, z)
        t_old = time.perf_counter() - t0
        print(f"  n = {n}, {len(V)} vertices -> {len(new)}: pairs above z {t_new:.3f} s, every pair {t_old:.3f} s, "
              f"ratio {t_new / t_old:.3f} ({'same vertices' if np.array_equal(new, old) else 'DIFFERENT VERTICES'})")

    whole_allocator()


if __name__ == "__main__":
    main()
