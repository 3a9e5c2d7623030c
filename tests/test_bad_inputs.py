"""Issue 15: every mistake gets a one-line answer before any work is done.

A table of bad inputs across the command line, study files and the Python API. For each case the
test asserts the exception class (API) or the exit code (CLI), that the message names the field
and the offending value, that no traceback is printed, and -- by replacing every allocator,
the Monte Carlo check and every seed study with a sentinel that fails the test when called --
that the error comes before any long computation starts.
"""
from __future__ import annotations

import argparse
import dataclasses
import inspect
from pathlib import Path

import pytest

import evotol.studies
import evotol.studyfile
import evotol.studyfile.run
from evotol.cli import main
from evotol.errors import ValidationError

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ucr3_example.toml"


class ComputationStarted(AssertionError):
    """Raised by the sentinels: the bad input was not caught before the computation."""


def _sentinel(*args, **kwargs):
    raise ComputationStarted("a long computation started before the bad input was reported")


def _sentinel_like(func):
    """A sentinel with ``func``'s signature (the study file's keyword checks read it)."""
    def sentinel(*args, **kwargs):
        _sentinel()
    sentinel.__signature__ = inspect.signature(func)
    return sentinel


@pytest.fixture
def no_computation(monkeypatch):
    """Every allocator, Monte Carlo and seed study fails the test if it is reached."""
    run = evotol.studyfile.run                  # the module that calls the methods and the Monte Carlo
    monkeypatch.setattr(run, "METHODS", {m: _sentinel_like(f) for m, f in run.METHODS.items()})
    monkeypatch.setattr(run, "allocate_nsga2", _sentinel_like(run.allocate_nsga2))
    monkeypatch.setattr(run, "verify", _sentinel_like(run.verify))
    fake = {n: dataclasses.replace(s, compute=_sentinel)
            for n, s in evotol.studies.available().items()}
    monkeypatch.setattr(evotol.studies, "available", lambda: fake)


def _run_cli(argv, capsys) -> tuple[int, str]:
    """Exit code and stderr of ``evotol ARGV`` (argparse errors exit via SystemExit)."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    captured = capsys.readouterr()
    return code, captured.err


def _study(tmp_path: Path, *edits: tuple[str, str], append: str = "") -> str:
    """The example study file with text replacements (each must match), written to tmp_path."""
    text = EXAMPLE.read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    f = tmp_path / "study.toml"
    f.write_text(text + append)
    return str(f)


def _entries_csv(tmp_path: Path) -> str:
    f = tmp_path / "plain.csv"
    f.write_text("a,b,p_max\n1,2,0.1\n2,3,0.2\n")
    return str(f)


# --- command line ---------------------------------------------------------------------------
# each case: argv builder (tmp_path -> argv), expected exit code, strings the message must name
CLI_CASES = {
    "run a folder": (lambda d: ["run", str(d)], 2, ["study file", "{d}", "not a folder"]),
    "run a missing file": (lambda d: ["run", str(d / "nope.toml")], 2, ["study file", "nope.toml"]),
    "run --out under /proc": (lambda d: ["run", str(EXAMPLE), "--out", "/proc/evotol-x"], 2, ["--out", "/proc/evotol-x"]),
    "run --out an existing file": (lambda d: ["run", str(EXAMPLE), "--out", str(EXAMPLE)], 2, ["--out", "ucr3_example.toml", "not an existing file"]),
    "run --seed -1": (lambda d: ["run", str(EXAMPLE), "--seed", "-1"], 2, ["--seed", "'-1'"]),
    "run --seed 1.5": (lambda d: ["run", str(EXAMPLE), "--seed", "1.5"], 2, ["--seed", "'1.5'"]),
    "run --seed abc": (lambda d: ["run", str(EXAMPLE), "--seed", "abc"], 2, ["--seed", "'abc'"]),
    "run --seed 2**32": (lambda d: ["run", str(EXAMPLE), "--seed", str(2 ** 32)], 2, ["--seed", str(2 ** 32)]),
    "reproduce --out a file": (lambda d: ["reproduce", "yao2013", "--out", str(EXAMPLE)], 2, ["--out", "ucr3_example.toml"]),
    "reproduce --out under /proc": (lambda d: ["reproduce", "yao2013", "--out", "/proc/evotol-x"], 2, ["--out", "/proc/evotol-x"]),
    "reproduce --seed -3": (lambda d: ["reproduce", "yao2013", "--seed", "-3"], 2, ["--seed", "'-3'"]),
    "reproduce unknown study": (lambda d: ["reproduce", "yao2031", "--out", str(d)], 2, ["study", "'yao2031'", "yao2013"]),
    "reproduce --scheduler notaurl": (lambda d: ["reproduce", "yao2013", "--scheduler", "notaurl"], 2, ["--scheduler", "'notaurl'", "tcp://host:port"]),
    "reproduce --scheduler without port": (lambda d: ["reproduce", "yao2013", "--scheduler", "tcp://localhost"], 2, ["--scheduler", "'tcp://localhost'"]),
    "reproduce --scheduler http": (lambda d: ["reproduce", "yao2013", "--scheduler", "http://localhost:8786"], 2, ["--scheduler", "http://localhost:8786"]),
    "reproduce --scheduler bad port": (lambda d: ["reproduce", "yao2013", "--scheduler", "tcp://localhost:99999"], 2, ["--scheduler", "tcp://localhost:99999"]),
    "reproduce --scheduler nobody there": (lambda d: ["reproduce", "yao2013", "--out", str(d), "--scheduler", "tcp://127.0.0.1:1"], 2,
                                           ["--scheduler", "tcp://127.0.0.1:1", "Dask scheduler"]),
    "filter missing entries": (lambda d: ["filter", str(d / "none.parquet"), "a > 1"], 2, ["entries", "none.parquet"]),
    "filter CSV without metadata": (lambda d: ["filter", _entries_csv(d), "a > 1"], 2, ["--inputs", "--objectives", "plain.csv", "p_max"]),
    "filter --html under /proc": (lambda d: ["filter", _entries_csv(d), "a > 1", "--inputs", "a,b", "--html", "/proc/x/kept.html"], 2,
                                  ["--html", "/proc/x/kept.html"]),
    "filter --html a folder": (lambda d: ["filter", _entries_csv(d), "a > 1", "--inputs", "a,b", "--html", str(d)], 2, ["--html", "{d}", "not a folder"]),
    "filter --out under /proc": (lambda d: ["filter", _entries_csv(d), "a > 1", "--inputs", "a,b", "--out", "/proc/x/kept.csv"], 2,
                                 ["--out", "/proc/x/kept.csv"]),
    "describe unknown robot": (lambda d: ["describe", "hexapod"], 2, ["robot.model", "'hexapod'", "ucr3"]),
    "describe --set unknown argument": (lambda d: ["describe", "ucr3", "--set", "colour=1"], 2, ["--set", "colour", "UCR3"]),
    "describe --set without =": (lambda d: ["describe", "ucr3", "--set", "variant"], 2, ["--set", "'variant'", "KEY=VALUE"]),
    "describe --set bad variant": (lambda d: ["describe", "ucr3", "--set", "variant=papr"], 2, ["variant", "'papr'"]),
}


@pytest.mark.parametrize("case", list(CLI_CASES))
def test_cli_bad_input(case, tmp_path, capsys, no_computation):
    build, code, names = CLI_CASES[case]
    got, err = _run_cli(build(tmp_path), capsys)
    assert got == code, err
    assert "Traceback" not in err
    message = err.strip().splitlines()[-1]            # the one-line answer is the last line
    for name in names:
        assert name.format(d=tmp_path) in message, (name, message)


# --- study files ----------------------------------------------------------------------------
STUDY_CASES = {
    "unknown measure": ((("measure = \"rss\"", "measure = \"maximum\""),), ["requirement.measure", "'maximum'"]),
    "unknown robot": ((("model = \"ucr3\"", "model = \"hexapod\""),), ["robot.model", "'hexapod'", "ucr3"]),
    "unknown source": ((("[sources.R1]", "[sources.R9]"),), ["sources.R9", "'R9'", "R1"]),
    "negative cost coefficient": ((("a1 = 0.5", "a1 = -0.5"),), ["exponential.a1", "-0.5"]),
    "unknown cost model": ((("model = \"exponential\"\na0 = 1.9", "model = \"expo\"\na0 = 1.9"),), ["model", "'expo'"]),
    "unknown method": ((("sensitivity = {}", "sensitivty = {}"),), ["methods.sensitivty", "did you mean 'sensitivity'"]),
    "GA keyword typo": ((("ga = { pop_size = 60", "ga = { pop_sise = 60"),), ["methods.ga.pop_sise", "60", "did you mean 'pop_size'"]),
    "NSGA-II keyword typo": ((("nsga2 = { pop_size = 60, n_gen = 60 }", "nsga2 = { pop_size = 60, ngen = 60 }"),),
                             ["methods.nsga2.ngen", "60", "did you mean 'n_gen'"]),
    "optimum keyword typo": ((("optimum = {}", "optimum = { max_round = 5 }"),), ["methods.optimum.max_round", "5", "did you mean 'max_rounds'"]),
    "method not a table": ((("optimum = {}", "optimum = 3"),), ["methods.optimum", "3", "a table"]),
    "verify keyword typo": ((("n_samples = 500", "n_sample = 500"),), ["verify.n_sample", "500", "did you mean 'n_samples'"]),
    "verify sets the seed": ((("method = \"lhs\"", "seed = 3"),), ["verify.seed", "3"]),
    "negative position requirement": ((("position = 5e-5", "position = -5e-5"),), ["requirement.position", "-5e-05"]),
    "lower above upper": ((("lower = 1e-6", "lower = 3e-4"),), ["lower", "0.0003"]),
    "robot argument typo": ((("variant = \"verified\"", "variant = \"verifed\""),), ["variant", "'verifed'"]),
    "poses without a kind": ((("grid = [5, 5, 3]", "grud = [5, 5, 3]"),), ["poses", "grud"]),
    "grid of wrong length": ((("grid = [5, 5, 3]", "grid = [5, 5]"),), ["grid", "[5, 5]"]),
    "pose outside the workspace": ((("grid = [5, 5, 3]", "list = [[0.0, 0.0, 9.0]]"),), ["pose", "9.0"]),
    "GA budget below the cheapest design": ((("ga = { pop_size = 60", "ga = { budget = 1e-3, pop_size = 60"),),
                                            ["methods.ga.budget", "0.001", "cheapest design"]),
    "optimum budget NaN": ((("optimum = {}", "optimum = { budget = nan }"),), ["methods.optimum.budget", "nan"]),
    "sensitivity budget negative": ((("sensitivity = {}", "sensitivity = { budget = -2.0 }"),), ["methods.sensitivity.budget", "-2.0"]),
    # a batch of 0 ended in "argmin of an empty sequence", a text rel_gap in a TypeError, after the other methods ran
    "monotone batch 0": ((("optimum = {}", "optimum = {}\nmonotone = { batch = 0 }"),), ["methods.monotone", "batch = 0", "integer >= 1"]),
    "monotone rel_gap text": ((("optimum = {}", "optimum = {}\nmonotone = { rel_gap = \"1 %\" }"),),
                              ["methods.monotone", "rel_gap = '1 %'", "a number > 0"]),
    "locked above upper": ((("locked = 2e-5", "locked = 5e-4"),), ["tolerances['R1'].locked", "0.0005", "0.0002"]),
    "locked below lower": ((("locked = 2e-5", "locked = 1e-7"),), ["tolerances['R1'].locked", "1e-07"]),
    "grid = 3.5": ((("grid = [5, 5, 3]", "grid = 3.5"),), ["grid counts", "3.5"]),
    "grid with a fraction": ((("grid = [5, 5, 3]", "grid = [5, 5, 2.5]"),), ["grid counts", "2.5"]),
    "latin_hypercube = 20.5": ((("grid = [5, 5, 3]", "latin_hypercube = 20.5"),), ["latin_hypercube n", "20.5"]),
    "bounds for an unknown group": ((("[bounds]                  #", "[bounds.Ujoint]\nupper = 1e-4\n[bounds]  #"),), ["bounds.Ujoint", "did you mean 'U joint'"]),
    "bounds key typo": ((("upper = 2e-4", "uper = 2e-4"),), ["bounds.uper", "did you mean 'upper'"]),
    "bounds group key typo": ((("[bounds]                  #", "[bounds.\"U joint\"]\nlowr = 1e-6\n[bounds]  #"),), ["bounds.U joint.lowr", "did you mean 'lower'"]),
    "bounds not a number": ((("lower = 1e-6", "lower = \"1e-6\""),), ["bounds.lower", "'1e-6'"]),
    # issue-10 cases (tolerance specification, landed by "tolspec"): checked here end to end
    "unknown top-level table": ((("[requirement]", "[requirment]"),), ["requirment", "did you mean 'requirement'"]),
    "negative seed in the file": ((("seed = 0", "seed = -1"),), ["seed = -1", "non-negative integer"]),
    "fractional seed in the file": ((("seed = 0", "seed = 1.5"),), ["seed = 1.5", "non-negative integer"]),
    "empty pose list": ((("grid = [5, 5, 3]", "list = []"),), ["poses", "at least one workspace pose"]),
    "requirement no design meets": ((("position = 5e-5 ", "position = 1e-8 "), ("locked = 2e-5", "upper = 1e-4")),
                                    ["infeasible", "1e-08", "lower bound", "pose"]),
    "source key typo": ((("locked = 2e-5", "lockd = 2e-5"),), ["sources.R1.lockd", "did you mean 'locked'"]),
    "invalid TOML": ((("name = \"ucr3_example\"", "name = ucr3_example"),), ["study file", "valid TOML"]),
}


@pytest.mark.parametrize("case", list(STUDY_CASES))
def test_study_file_bad_input(case, tmp_path, capsys, no_computation):
    edits, names = STUDY_CASES[case]
    code, err = _run_cli(["run", _study(tmp_path, *edits), "--out", str(tmp_path)], capsys)
    assert code == 2, err
    assert "Traceback" not in err
    message = err.strip().splitlines()[-1]
    assert message.startswith("evotol: error: "), message
    for name in names:
        assert name in message, (name, message)


def test_argparse_type_errors_are_argument_type_errors():
    """The --seed/--scheduler types raise argparse's own error class, so argparse prints usage + one line."""
    from evotol.cli import argument_types as arguments
    with pytest.raises(argparse.ArgumentTypeError, match="'-1'"):
        arguments.seed("-1")
    with pytest.raises(argparse.ArgumentTypeError, match="notaurl"):
        arguments.scheduler("notaurl")
    assert arguments.seed("7") == 7
    assert arguments.parse_scheduler("tcp://10.0.0.5:8786") == ("tcp", "10.0.0.5", 8786)


# --- Python API -------------------------------------------------------------------------------
def _api_problem(locked=None, measure="worst_case", position=1e-3):
    import numpy as np

    import evotol.cost_models as cm
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
    from tests.toy_robot import ToyRobot

    r = ToyRobot(dims=(1, 1, 2))
    tol = {s.name: Tolerance(cm.ExponentialCost(1.0, 0.5, scale=1e-3), 1e-5, 1e-2, locked=(locked or {}).get(s.name))
           for s in r.sources}
    return ToleranceProblem(r, tol, Requirement(position=position, measure=measure), np.array([[0.0], [1.0]]))


def _api(name):
    """Calls that must fail; imported lazily so a collection error names the case."""
    import numpy as np

    import evotol.cost_models as cm
    from evotol import allocators as al
    from evotol.verification.montecarlo import verify
    from evotol.core.problem import Requirement, Tolerance, ToleranceProblem
    from evotol.robots import registry
    from evotol.robots.ucr3 import UCR3
    from tests.toy_robot import ToyRobot

    P = _api_problem
    t_ok = {n: 1e-4 for n in ("s0", "s1", "s2")}
    calls = {
        "ga budget below cheapest": lambda: al.allocate_ga(P(), budget=1e-3, pop_size=8, n_gen=2),
        "optimum budget NaN": lambda: al.allocate_optimum(P(), budget=float("nan")),
        "sensitivity budget below cheapest": lambda: al.allocate_sensitivity(P(), budget=1e-6),
        "equal budget inf": lambda: al.allocate_equal(P(), budget=float("inf")),
        "lagrange budget a string": lambda: al.allocate_lagrange(P(), budget="5"),
        "proportional budget zero": lambda: al.allocate_proportional(P(), budget=0.0),
        "ga pop_size too small": lambda: al.allocate_ga(P(), pop_size=2),
        "ga unknown operators": lambda: al.allocate_ga(P(), operators="papr"),
        "locked above upper": lambda: P(locked={"s0": 0.5}),
        "negative requirement": lambda: P(position=-1e-3),
        "unknown measure": lambda: P(measure="max"),
        "tolerance for an unknown source": lambda: ToleranceProblem(
            ToyRobot(dims=(1,)), {"s0": Tolerance(cm.ExponentialCost(1.0, 0.5), 1e-5, 1e-2),
                                  "s9": Tolerance(cm.ExponentialCost(1.0, 0.5), 1e-5, 1e-2)},
            Requirement(position=1e-3), np.array([[0.5]])),
        "verify n_samples 0": lambda: verify(P(), t_ok, n_samples=0),
        "verify unknown method": lambda: verify(P(), t_ok, method="sobol7"),
        "grid 3.5": lambda: UCR3().workspace.grid(3.5),
        "negative cost decay": lambda: cm.ExponentialCost(1.0, -0.5),
        "unknown robot": lambda: registry.get("hexapod"),
        "pose outside the workspace": lambda: UCR3().check_poses([[0.0, 0.0, 9.0]]),
    }
    return calls[name]


def _kinematics_error():
    from evotol.errors import KinematicsError
    return KinematicsError


API_CASES = {   # name: (exception class, strings the message must contain)
    "ga budget below cheapest": (ValidationError, ["budget", "0.001", "cheapest design"]),
    "optimum budget NaN": (ValidationError, ["budget", "nan"]),
    "sensitivity budget below cheapest": (ValidationError, ["budget", "1e-06", "cheapest design"]),
    "equal budget inf": (ValidationError, ["budget", "inf"]),
    "lagrange budget a string": (ValidationError, ["budget", "'5'"]),
    "proportional budget zero": (ValidationError, ["budget", "0.0"]),
    "ga pop_size too small": (ValidationError, ["pop_size", "2"]),
    "ga unknown operators": (ValidationError, ["operators", "'papr'"]),
    "locked above upper": (ValidationError, ["tolerances['s0'].locked", "0.5", "0.01"]),
    "negative requirement": (ValidationError, ["requirement.position", "-0.001"]),
    "unknown measure": (ValidationError, ["requirement.measure", "'max'"]),
    "tolerance for an unknown source": (ValidationError, ["s9", "s0"]),
    "verify n_samples 0": (ValidationError, ["n_samples", "0"]),
    "verify unknown method": (ValidationError, ["method", "'sobol7'"]),
    "grid 3.5": (ValidationError, ["grid counts", "3.5"]),
    "negative cost decay": (ValidationError, ["a1", "-0.5"]),
    "unknown robot": (ValidationError, ["robot.model", "'hexapod'", "ucr3"]),
    "pose outside the workspace": ("KinematicsError", ["pose", "9.0", "Zc"]),
}


@pytest.mark.parametrize("case", list(API_CASES))
def test_api_bad_input(case, monkeypatch):
    import evotol.allocators.ga as ga_module

    expected, names = API_CASES[case]
    expected = _kinematics_error() if expected == "KinematicsError" else expected
    monkeypatch.setattr(ga_module, "GA", _sentinel)          # the GA must not start
    with pytest.raises(expected) as info:
        _api(case)()
    message = str(info.value)
    assert "\n" not in message, message
    for name in names:
        assert name in message, (name, message)


def test_the_sentinels_catch_a_computation_that_starts(tmp_path, no_computation):
    """The table's "before any work" rests on the sentinels: the unedited example study does reach
    a method under them, so a bad input that slipped past the checks would fail its row (this
    replaces a count of the table's own rows, which could not fail)."""
    with pytest.raises(ComputationStarted):
        main(["run", _study(tmp_path), "--out", str(tmp_path)])


@pytest.fixture(scope="module")
def spawned_worker():
    """One spawned worker process for the cases below (issue 43: one start instead of three). An error that
    could not cross the boundary would break the pool (BrokenProcessPool) and fail every later case too."""
    import concurrent.futures as cf
    import multiprocessing as mp

    with cf.ProcessPoolExecutor(1, mp_context=mp.get_context("spawn")) as pool:
        yield pool


@pytest.mark.parametrize("kind, field, text", [
    ("validation", "field", "grid = -1: expected a positive integer"),
    ("kinematics", "poses", "pose out of reach"),
    ("infeasible", "smallest_error", "infeasible: position <= 1e-06 m cannot be met"),
])
def test_errors_cross_a_process_boundary_as_themselves(kind, field, text, spawned_worker):
    """An error raised in a worker process (the executor's pools, a DOE chunk) reaches the parent as
    the same class with the same fields and message; before, ValidationError and InfeasibleError
    could not be unpickled and the pool broke (BrokenProcessPool)."""
    import pickle

    from evotol.errors import EvotolError
    from tests.worker_errors import raise_in_worker

    with pytest.raises(EvotolError) as local:
        raise_in_worker(kind)
    again = pickle.loads(pickle.dumps(local.value))
    assert type(again) is type(local.value) and str(again) == str(local.value)
    assert getattr(again, field) == getattr(local.value, field)
    with pytest.raises(type(local.value), match=text.replace("(", r"\(")) as remote:
        spawned_worker.submit(raise_in_worker, kind).result()
    assert getattr(remote.value, field) == getattr(local.value, field)
