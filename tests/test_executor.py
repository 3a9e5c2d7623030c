"""The one executor (evotol._runtime.executor): order, shared arguments, backends, the resumable chunk store."""
import pickle

import numpy as np
import pandas as pd
import pytest

from evotol.design import Factor, Objective
from evotol.design.nsga import DesignProblem
from evotol.errors import ValidationError
from evotol._runtime.executor import ChunkStore, parallel_map, run_chunks, worker_count


def _scaled(k, x):
    return k * x


def test_run_chunks_hands_every_item_once_with_the_shared_arguments():
    got = {}
    for workers in (1, 2):
        got.clear()
        backend = run_chunks(_scaled, [3, 1, 2, 5], got.__setitem__, common=(10,), workers=workers)
        assert got == {0: 30, 1: 10, 2: 20, 3: 50}
        assert backend == ("in-process" if workers == 1 else "2 local processes")
    assert parallel_map(_scaled, [3, 1, 2], common=(-1,), workers=2) == [-3, -1, -2]


@pytest.mark.parametrize("bad", [0, -2, "many"])
def test_worker_count_names_a_bad_value(bad):
    with pytest.raises(ValidationError, match="workers"):
        worker_count(bad)


def test_chunk_store_resumes_only_with_the_same_manifest(tmp_path):
    a = pd.DataFrame({"x": [1.0, 2.0]})
    store = ChunkStore(tmp_path, key="abc", n_entries=4)
    assert store.open() == {}
    store.save(1, a)
    again = ChunkStore(tmp_path, key="abc", n_entries=4).open()
    assert list(again) == [1] and again[1].equals(a)
    # a chunk cut short by a kill is dropped (evaluated again), not read as data
    (tmp_path / "chunk_00002.parquet").write_bytes(b"PAR1 truncated")
    assert list(ChunkStore(tmp_path, key="abc", n_entries=4).open()) == [1]
    assert not (tmp_path / "chunk_00002.parquet").exists()
    # another study's manifest: the old chunks do not belong to it
    assert ChunkStore(tmp_path, key="other", n_entries=4).open() == {}
    assert not list(tmp_path.glob("chunk_*.parquet"))


class _Sum:
    def __call__(self, X):
        return pd.DataFrame({"cost": 1.0 / X.to_numpy().sum(axis=1), "size": X.to_numpy().sum(axis=1)})


def test_design_problem_pickles_to_workers():
    """The pymoo problem of evotol.design.nsga2 is a module-level class: it survives pickling and
    evaluates the same objectives afterwards (cost = 1/Σx, size = Σx here)."""
    f = [Factor("a", low=1.0, high=2.0), Factor("b", low=0.0, high=4.0)]
    p = DesignProblem(f, _Sum(), [Objective("cost"), Objective("size", -1)])
    q = pickle.loads(pickle.dumps(p))
    U = np.array([[0.0, 0.0], [1.0, 0.5]])
    out = q.evaluate(U, return_as_dictionary=True)
    s = np.array([1.0, 4.0])
    np.testing.assert_allclose(out["F"], np.column_stack([1 / s, -s]))
    assert (out["G"] < 0).all()
