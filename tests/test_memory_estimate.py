"""A study that would need more memory than the machine has is told so before the first method, with its
estimate (issue 43 item 4). The estimate is twice the worst-case support coefficients the measures keep
(position and orientation, each at most the cache's size) plus the sensitivities and results; here it is checked against the arrays the problem
really builds, and the refusal against a spy on the first method."""
from __future__ import annotations

import time

import numpy as np
import pytest

import evotol.core.memory as memory
from evotol.errors import ValidationError
from evotol.studyfile.problem import load_problem
from evotol.studyfile.run import _run_claimed
from tests.test_combinations import STUDIES, ur5


def test_estimate_is_twice_the_coefficients_the_problem_builds():
    p = load_problem(ur5(), base_dir=STUDIES)
    built = sum(sum(a.nbytes for a in p.coefficients(c) if isinstance(a, np.ndarray) and a.ndim == 3)
                for c in ("position", "orientation"))
    kept = p.n_poses * (8 * 6 * p.error_model.n_columns + memory.PER_POSE_BYTES)      # J and the results
    assert memory.study_bytes(p) == pytest.approx(memory.WORKING_FACTOR * built + kept, rel=1e-12)


def test_a_study_larger_than_the_memory_is_refused_before_the_first_method(tmp_path, monkeypatch):
    import evotol.allocators as allocators

    spec = ur5()
    spec["methods"] = {"optimum": {}}
    p = load_problem(spec, base_dir=STUDIES)
    need = memory.study_bytes(p)
    monkeypatch.setattr(memory, "available_bytes", lambda: int(need / 2))          # half of what it needs
    work = []
    monkeypatch.setattr(allocators, "allocate_optimum", lambda *a, **k: work.append("optimum"))
    with pytest.raises(ValidationError, match=r"^poses = '2 poses': expected at most about 0 poses here: .* need "
                                              r"about .* GiB .* is available") as e:
        _run_claimed(spec, tmp_path / "m.toml", tmp_path, "m", 0, time.perf_counter(), False)
    assert "\n" not in str(e.value) and not work and not list(tmp_path.iterdir())
    monkeypatch.setattr(memory, "available_bytes", lambda: int(need * 2))           # twice: it runs
    memory.check_memory(p)
    big = p.at_poses(np.repeat(p.poses, 10, axis=0))                                 # 20 poses
    per_pose = memory.study_bytes(big) / 20
    with pytest.raises(ValidationError, match=r"^poses = '20 poses': expected at most about 7 poses here"):
        memory.check_memory(big, available=int(7.5 * per_pose / memory.USABLE_SHARE))
