"""The polyblock cut of the monotone allocator (evotol/allocators/monotone.py::_cut, issue 43): each new vertex
compared only with the vertices that can dominate it, against every pair (the cut before e5bb283), on the same
polyblocks. Prints per dimension the vertices, both times, their ratio and whether the vertices kept are the same.

    python benchmarks/bench_polyblock.py

The polyblocks are built by cutting the unit box at random points z (seeded) until it has at least 300 vertices (a few hundred to a thousand), as
the polyblock does on a 36-source problem in its first two rounds (741 vertices on the ISO example).
"""
from __future__ import annotations

import time

import numpy as np

from evotol.allocators.monotone import _cut, new_vertices


def cut_every_pair(V: np.ndarray, z: np.ndarray, chunk: int = 256) -> np.ndarray:
    """The cut with each new vertex compared with every vertex (the dominance check before e5bb283)."""
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


def main() -> None:
    rng = np.random.default_rng(0)
    print("polyblock cut (monotone allocator): per coordinate vs every pair, one cut, same polyblock")
    for n in (12, 24, 36):
        V, z = polyblock_of(n, 300, rng)
        t0 = time.perf_counter()
        new = _cut(V, z)
        t_new = time.perf_counter() - t0
        t0 = time.perf_counter()
        old = cut_every_pair(V, z)
        t_old = time.perf_counter() - t0
        print(f"  n = {n}, {len(V)} vertices -> {len(new)}: per coordinate {t_new:.3f} s, every pair {t_old:.3f} s, "
              f"ratio {t_new / t_old:.3f} ({'same vertices' if np.array_equal(new, old) else 'DIFFERENT VERTICES'})")


if __name__ == "__main__":
    main()
