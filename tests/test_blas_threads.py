"""BLAS limited to one thread inside evotol's hot paths (evotol/_runtime/blas_threads.py), through one
thread-pool controller a process that is made again after new imports: every BLAS library is limited,
one that an import loads after the first use too, and the limits are restored on the way out."""
from __future__ import annotations

import json
import subprocess
import sys
import textwrap

from threadpoolctl import threadpool_info, threadpool_limits

from evotol._runtime.blas_threads import one_blas_thread, single_threaded_blas


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_one_thread_inside_and_the_earlier_limits_after_even_nested():
    import numpy  # noqa: F401  (NumPy's BLAS is loaded)

    @single_threaded_blas
    def inner():
        return _blas_threads()

    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        with one_blas_thread():
            assert set(_blas_threads()) == {1}
            assert set(inner()) == {1}
            assert set(_blas_threads()) == {1}          # the inner exit restores the outer limit
        assert _blas_threads() == before


def test_a_blas_library_imported_after_the_first_use_is_limited_too():
    """In a new process: NumPy's BLAS only, a first use (the controller is made), then SciPy's linalg,
    whose wheel loads a BLAS library of its own; inside the next use every library has one thread."""
    code = textwrap.dedent("""
        import json
        import numpy
        from threadpoolctl import threadpool_info, threadpool_limits
        from evotol._runtime.blas_threads import one_blas_thread
        threadpool_limits(limits=2, user_api="blas")
        with one_blas_thread():
            pass
        import scipy.linalg
        threadpool_limits(limits=2, user_api="blas")
        libs = lambda: {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}
        before = libs()
        with one_blas_thread():
            inside = libs()
        print(json.dumps([before, inside, libs()]))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    before, inside, after = json.loads(out)
    assert set(inside) == set(before) and set(inside.values()) == {1}
    assert after == before
    print(f"{len(before)} BLAS libraries: {sorted(before)}")
