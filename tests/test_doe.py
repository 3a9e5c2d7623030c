"""Design-of-experiments entries and their evaluation (evotol.design; Deng 2012 Sec. VII.1).

The evaluator used here is a closed-form serial chain: planar, parallel joint axes, clearances
locked in rotation. Its clearance disks (radius Δb_xy, in the plane) and segments (half-length
Δb_z, along the axes) add as a Minkowski sum -- a cylinder -- so the maximum positional error is
exactly sqrt((Σ Δb_xy)² + (Σ Δb_z)²) (Deng 2012 eqs. III.5-III.6, III.16 with identity adjoints
for a pure translation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest

from evotol import design as doe
from evotol.design import Factor, Objective
from evotol.errors import KinematicsError, ValidationError

LEVELS_XY = (1e-4, 1e-3, 1e-2, 1e-1)
LEVELS_Z = (1e-3, 1e-1)


def thesis_factors(n_joints: int = 5):
    """The 5-bar factor layout of Deng 2012 Sec. VII.1.2: Δb_xy on 4 levels, Δb_z on 2 (mm)."""
    xy = [Factor(f"db_xy_{j}_mm", LEVELS_XY, log=True, si_scale=1e-3) for j in "ABCDE"[:n_joints]]
    z = [Factor(f"db_z_{j}_mm", LEVELS_Z, log=True, si_scale=1e-3) for j in "ABCDE"[:n_joints]]
    return xy + z


@dataclass(frozen=True)
class SerialChainClearance:
    """p_max (mm) of a translational-clearance serial chain: sqrt((Σ Δb_xy)² + (Σ Δb_z)²)."""

    fail_above_mm: float = np.inf     # entries with p_max above this raise KinematicsError

    def __call__(self, X: pd.DataFrame) -> pd.DataFrame:
        xy = X[[c for c in X if c.startswith("db_xy")]].to_numpy().sum(axis=1)
        z = X[[c for c in X if c.startswith("db_z")]].to_numpy().sum(axis=1)
        p = np.hypot(xy, z)
        if np.any(p > self.fail_above_mm):
            raise KinematicsError(f"pose unreachable with clearances {p.max():.3g} mm", poses=None)
        return pd.DataFrame({"p_max_mm": p, "p_xy_mm": xy})


@dataclass(frozen=True)
class InterruptAfter:
    """Evaluator that stops the study (KeyboardInterrupt) once entry ``stop_at`` is reached."""

    stop_at: int

    def __call__(self, X):
        if X["entry"].max() >= self.stop_at:
            raise KeyboardInterrupt
        return SerialChainClearance()(X)

    def cache_key(self):                # same study as SerialChainClearance for resuming
        return repr(SerialChainClearance())


def test_full_factorial_counts_thesis_sec_VII_1_2():
    """4^5 x 2^5 = 32 768 entries (Sec. VII.1.2), every level equally often, all distinct."""
    f = thesis_factors()
    E = doe.full_factorial(f)
    assert len(E) == doe.n_factorial(f) == 32768
    assert not E.drop(columns="entry").duplicated().any()
    for fac in f:
        counts = E[fac.name].value_counts()
        assert set(counts.index) == set(fac.levels)
        assert counts.nunique() == 1 and counts.iloc[0] == 32768 // len(fac.levels)
    # mixed-radix ids decode to the same rows
    ids = np.array([0, 1, 12345, 32767])
    assert E.iloc[ids].reset_index(drop=True).equals(doe.factorial_entries(f, ids))


def test_random_subset_is_a_seeded_subset_of_the_factorial_fig_VII_2():
    """The thesis's 1000-entry sample: distinct factorial entries, reproducible from the seed."""
    f = thesis_factors()
    a, b, c = doe.random_subset(f, 1000, seed=3), doe.random_subset(f, 1000, seed=3), doe.random_subset(f, 1000, seed=4)
    assert len(a) == 1000 and a["entry"].is_unique
    assert a.equals(b) and not a.equals(c)
    full = doe.full_factorial(f).set_index("entry")
    assert full.loc[a["entry"]].reset_index(drop=True).equals(a.drop(columns="entry"))
    with pytest.raises(ValidationError):
        doe.random_subset(f, 40000)


def test_latin_hypercube_stratifies_each_factor_in_log_space():
    """Each of the n equal strata of every factor holds exactly one entry (log10 for log factors)."""
    f = [Factor("t_mm", low=1e-4, high=1e-1, log=True), Factor("L_mm", low=50, high=200),
         Factor("lvl", levels=(1.0, 2.0, 3.0, 4.0))]
    n = 40
    E = doe.latin_hypercube(f, n, seed=1)
    u = (np.log10(E["t_mm"]) + 4) / 3
    assert sorted(np.floor(u * n).astype(int)) == list(range(n))
    u = (E["L_mm"] - 50) / 150
    assert sorted(np.floor(u * n).astype(int)) == list(range(n))
    assert (E["lvl"].value_counts() == n // 4).all()


def test_evaluate_matches_closed_form_in_process_and_on_local_processes():
    """Chunked evaluation on 1 and 2 local processes equals the closed form entry by entry."""
    f = thesis_factors(3)
    E = doe.full_factorial(f)                     # 512 entries
    xy = E[[c for c in E if c.startswith("db_xy")]].sum(axis=1)
    z = E[[c for c in E if c.startswith("db_z")]].sum(axis=1)
    a = doe.evaluate(E, SerialChainClearance(), workers=1, chunk_size=100, progress=False)
    b = doe.evaluate(E, SerialChainClearance(), workers=2, chunk_size=64, progress=False)
    np.testing.assert_allclose(a["p_max_mm"], np.hypot(xy, z), rtol=1e-15)
    pd.testing.assert_frame_equal(a, b)
    assert a["feasible"].all() and (a["error"] == "").all()
    assert a.attrs["evotol"]["objectives"] == ["p_max_mm", "p_xy_mm"]


def test_interrupted_study_resumes_from_saved_chunks(tmp_path):
    """An interruption keeps the finished chunks; the next run evaluates only the missing ones."""
    E = doe.full_factorial(thesis_factors(3))
    with pytest.raises(KeyboardInterrupt):
        doe.evaluate(E, InterruptAfter(stop_at=300), store=tmp_path, workers=1, chunk_size=100, progress=False)
    assert sorted(p.name for p in tmp_path.glob("chunk_*.parquet")) == ["chunk_00000.parquet", "chunk_00001.parquet", "chunk_00002.parquet"]
    log = doe.EvaluationLog()
    df = doe.evaluate(E, SerialChainClearance(), store=tmp_path, workers=1, chunk_size=100, progress=False, log=log)
    assert log.chunks_resumed == [0, 1, 2] and sorted(log.chunks_evaluated) == [3, 4, 5]
    ref = doe.evaluate(E, SerialChainClearance(), workers=1, chunk_size=100, progress=False)
    pd.testing.assert_frame_equal(df, ref)
    # a third run evaluates nothing
    log = doe.EvaluationLog()
    doe.evaluate(E, SerialChainClearance(), store=tmp_path, workers=1, chunk_size=100, progress=False, log=log)
    assert log.chunks_evaluated == [] and log.backend == "store"
    # other entries in the same store: the stale chunks are discarded, not mixed in
    log = doe.EvaluationLog()
    E2 = doe.full_factorial(thesis_factors(2))
    doe.evaluate(E2, SerialChainClearance(), store=tmp_path, workers=1, chunk_size=100, progress=False, log=log)
    assert log.chunks_resumed == [] and len(log.chunks_evaluated) == 1


def test_failed_entries_are_recorded_not_silent():
    """An entry whose evaluation raises KinematicsError gets feasible=False and the message."""
    E = doe.full_factorial(thesis_factors(2))
    df = doe.evaluate(E, SerialChainClearance(fail_above_mm=0.15), workers=1, chunk_size=8, progress=False)
    bad = np.hypot(E.filter(like="db_xy").sum(axis=1), E.filter(like="db_z").sum(axis=1)) > 0.15
    assert bad.any() and (~bad).any()
    assert (df["feasible"] == ~bad).all()
    assert df.loc[bad, "error"].str.contains("KinematicsError: pose unreachable").all()
    assert df.loc[~bad, "p_max_mm"].notna().all() and df.loc[bad, "p_max_mm"].isna().all()


def test_unreachable_entry_is_recorded_whatever_the_chunk_size():
    """The entry out of reach (p_max 1.001 mm > 0.5) gets its KinematicsError in ``error`` with chunks
    of 1, 2 (it is then alone in the last chunk) and 3 entries; the reachable ones keep their p_max."""
    E = pd.DataFrame({"entry": [0, 1, 2], "db_xy_A_mm": [0.01, 0.02, 1.0], "db_z_A_mm": [0.001, 0.001, 0.001]})
    for chunk_size in (1, 2, 3):
        df = doe.evaluate(E, SerialChainClearance(fail_above_mm=0.5), workers=1, chunk_size=chunk_size,
                          progress=False)
        assert df["feasible"].tolist() == [True, True, False]
        assert df["error"].tolist()[:2] == ["", ""]
        assert df["error"][2] == "KinematicsError: pose unreachable with clearances 1 mm"
        np.testing.assert_allclose(df["p_max_mm"][:2], np.hypot([0.01, 0.02], 0.001), rtol=1e-15)
        assert np.isnan(df["p_max_mm"][2])


@dataclass(frozen=True)
class OneRowTooMany:
    """A broken evaluator: one output row more than entries."""

    def __call__(self, X):
        return pd.DataFrame({"p_max_mm": np.zeros(len(X) + 1)})


def test_malformed_evaluator_output_is_raised_not_recorded():
    """An output with the wrong row count is a programming error: ValidationError naming the rows
    received and expected, with chunks of 3 entries and of 1 entry alike (never written to ``error``)."""
    E = doe.full_factorial(thesis_factors(1))     # 8 entries
    with pytest.raises(ValidationError, match=r"evaluator output = 'DataFrame with 4 rows': expected .* with 3 rows"):
        doe.evaluate(E, OneRowTooMany(), workers=1, chunk_size=3, progress=False)
    with pytest.raises(ValidationError, match=r"'DataFrame with 2 rows': expected .* with 1 rows"):
        doe.evaluate(E, OneRowTooMany(), workers=1, chunk_size=1, progress=False)
    with pytest.raises(ValidationError, match=r"evaluator output = 'list': expected a DataFrame"):
        doe.evaluate(E, lambda X: [0.0] * len(X), workers=1, chunk_size=4, progress=False)


def test_dask_cluster_gives_the_local_result():
    """Given a scheduler address the chunks run on a Dask cluster, with identical results."""
    import distributed      # a declared test dependency (pyproject [test]): missing = a failure, not a skip
    E = doe.full_factorial(thesis_factors(2))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        log = doe.EvaluationLog()
        d = doe.evaluate(E, SerialChainClearance(), scheduler=cluster.scheduler_address, chunk_size=16,
                         progress=False, log=log)
    assert log.backend.startswith("dask")
    pd.testing.assert_frame_equal(d, doe.evaluate(E, SerialChainClearance(), workers=1, progress=False))


def test_save_and_load_keep_factors(tmp_path):
    E = doe.full_factorial(thesis_factors(2))
    df = doe.evaluate(E, SerialChainClearance(), workers=1, progress=False)
    paths = doe.save_entries(df, tmp_path / "entries")
    back = doe.load_entries(paths["parquet"])
    pd.testing.assert_frame_equal(back, df)
    assert [f.name for f in doe.factors_of(back)] == [f.name for f in thesis_factors(2)]
    assert doe.factors_of(back)[0].log and doe.factors_of(back)[0].si_scale == 1e-3
    csv = doe.load_entries(paths["csv"])
    np.testing.assert_allclose(csv["p_max_mm"], df["p_max_mm"])


def test_factor_validation():
    with pytest.raises(ValidationError, match="positive value on a log-scaled"):
        Factor("t", low=0.0, high=1.0, log=True)
    with pytest.raises(ValidationError, match="levels or a"):
        Factor("t")
    with pytest.raises(ValidationError, match="identifier"):
        Factor("p max")
    with pytest.raises(ValidationError, match="unique"):
        doe.full_factorial([Factor("a", (1, 2)), Factor("a", (1, 2))])


@dataclass(frozen=True)
class CostAndError:
    """Two objectives with a known Pareto front: cost Σ 1/t_j (t in µm) and error Σ t_j."""

    def __call__(self, X):
        t = X.to_numpy() * 1e3
        return pd.DataFrame({"cost": (1.0 / t).sum(axis=1), "p_max_mm": X.to_numpy().sum(axis=1)})


def test_nsga2_reaches_the_closed_form_front_and_marks_a_knee():
    """For Σ t = P fixed, Σ 1/t is least at equal t: cost >= n²/P (µm), equality on the front."""
    f = [Factor(f"t{j}_mm", low=1e-4, high=1e-1, log=True) for j in range(3)]
    pf = doe.nsga2(f, CostAndError(), [Objective("cost", 1, log=True), Objective("p_max_mm", 1, log=True)],
                   pop_size=40, n_gen=40, seed=1)
    front = pf.table
    bound = 9.0 / (front["p_max_mm"] * 1e3)
    ratio = front["cost"] / bound
    assert (ratio >= 1 - 1e-12).all()
    assert np.median(ratio) < 1.05
    assert front["knee"].sum() >= 1 and (front["source"] == "NSGA-II").all()
    # the closest-to-ideal knee of a symmetric front x*y = const in log space sits mid-front
    k = front.loc[front["knee"], "p_max_mm"]
    lo, hi = np.log10(front["p_max_mm"].min()), np.log10(front["p_max_mm"].max())
    assert ((np.log10(k) > lo) & (np.log10(k) < hi)).any()
    # the one front type: its knees are the table's knee rows, its cheapest member the least cost
    assert list(pf.knees().index) == list(front.index[front["knee"]])
    assert pf.knee() in set(front.index[front["knee"]])
    assert pf.cheapest_feasible()["cost"] == front["cost"].min()


def test_knee_of_a_convex_front():
    """Front y = 1/x on [0.1, 10] (log-log symmetric): the ideal-point knee is x = 1."""
    x = np.geomspace(0.1, 10, 41)
    F = np.column_stack([x, 1 / x])
    knees = doe.knee_points(F, log=[True, True])
    from evotol.core.pareto import ideal_point_knee

    assert ideal_point_knee(F, log=[True, True]) == 20 and x[20] == pytest.approx(1.0)
    assert 20 in knees


def test_nsga2_on_local_processes_equals_in_process():
    """Splitting each generation over worker processes changes nothing (same seed, same front)."""
    f = [Factor(f"t{j}_mm", low=1e-4, high=1e-1, log=True) for j in range(3)]
    objs = [Objective("cost", 1, log=True), Objective("p_max_mm", 1, log=True)]
    a = doe.nsga2(f, CostAndError(), objs, pop_size=12, n_gen=3, seed=2)
    b = doe.nsga2(f, CostAndError(), objs, pop_size=12, n_gen=3, seed=2, workers=2)
    pd.testing.assert_frame_equal(a.table, b.table)


class _FailsAboveTenMicrons:
    """CostAndError, but no entry with t0 > 0.01 mm assembles (a KinematicsError for the batch)."""

    def __call__(self, X):
        from evotol.errors import KinematicsError

        if (X["t0_mm"] > 0.01).any():
            raise KinematicsError("t0 too loose to assemble")
        return CostAndError()(X)


class _NeverAssembles:
    def __call__(self, X):
        from evotol.errors import KinematicsError

        raise KinematicsError("never assembles")


@pytest.mark.parametrize("workers", [1, 2])
def test_nsga2_ranks_entries_that_fail_as_infeasible(workers):
    """Entries the evaluator cannot evaluate are infeasible, never on the front, and a batch in which
    every entry fails (it brings no objective column back) does not stop the search; when no
    entry at all can be evaluated the search says so in one line."""
    from evotol.errors import EvotolError

    f = [Factor(f"t{j}_mm", low=1e-4, high=1e-1, log=True) for j in range(3)]
    objs = [Objective("cost", 1, log=True), Objective("p_max_mm", 1, log=True)]
    pf = doe.nsga2(f, _FailsAboveTenMicrons(), objs, pop_size=8, n_gen=2, seed=0, workers=workers)
    front = pf.table
    assert len(front) >= 1 and (front["t0_mm"] <= 0.01).all() and front["feasible"].all()
    # the front's numbers are the evaluator's: cost = sum 1/t (t in µm), error = sum t (mm)
    t = front[["t0_mm", "t1_mm", "t2_mm"]].to_numpy()
    np.testing.assert_allclose(front["cost"], (1.0 / (t * 1e3)).sum(1), rtol=1e-12)
    np.testing.assert_allclose(front["p_max_mm"], t.sum(1), rtol=1e-12)
    with pytest.raises(EvotolError, match="no feasible entry"):
        doe.nsga2(f, _NeverAssembles(), objs, pop_size=8, n_gen=2, seed=0, workers=workers)
