"""The front door (issue 22): ``import evotol`` exposes what a user needs, lazily, and every class an
error message names can be imported as written."""
from __future__ import annotations

import importlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

import evotol

ROOT = Path(__file__).resolve().parent.parent
# dotted names in message strings: "an evotol.Requirement", "a evotol.robots.base.RobotErrorModel"
DOTTED = re.compile(r"[\"'][^\"']*?\b((?:evotol|robots|cost_models)(?:\.[a-z_][a-z0-9_]*)*\.[A-Z][A-Za-z0-9_]*[a-z][A-Za-z0-9_]*)\b")


@pytest.mark.parametrize("name", evotol.__all__)
def test_every_public_name_imports(name):
    obj = getattr(evotol, name)
    assert getattr(obj, "__name__", name) == name   # the object is what its name says, not an alias
    exec(f"from evotol import {name}", {})


def test_the_names_a_user_needs_are_public():
    need = {"Tolerance", "Requirement", "ToleranceProblem", "allocate_sensitivity", "allocate_optimum",
            "allocate_ga", "allocate_nsga2", "allocate_process_optimum", "allocate_process_ga", "process_front",
            "verify", "AllocationResult", "ParetoFront", "ValidationError", "KinematicsError", "InfeasibleError",
            "MechanismModel", "AssemblyFunction"}
    assert need <= set(evotol.__all__), need - set(evotol.__all__)


def test_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'allocate_magic'"):
        evotol.allocate_magic  # noqa: B018


def test_import_evotol_is_lazy():
    """``import evotol`` (and so ``evotol --help``'s start) loads none of the numerical stack."""
    code = "import sys, evotol; print(sorted(m for m in ('numpy', 'scipy', 'pymoo', 'pinocchio', 'pandas') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"


def test_cli_help_is_lazy():
    """``evotol --help`` builds every sub-command's parser without the numerical stack."""
    code = ("import sys\nfrom evotol.cli import build_parser\nbuild_parser().format_help()\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'pymoo', 'pinocchio', 'pandas', 'numba') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"


def _named_classes():
    found = set()
    for folder in ("evotol", "robots", "cost_models"):
        for path in (ROOT / folder).rglob("*.py"):
            for m in DOTTED.finditer(path.read_text(encoding="utf-8")):
                found.add((m.group(1), f"{path.relative_to(ROOT)}"))
    return sorted(found)


def test_error_messages_name_importable_classes():
    named = _named_classes()
    assert len(named) >= 4   # evotol.Requirement, evotol.Tolerance, evotol.robots.base.RobotErrorModel, ...
    bad = []
    for dotted, where in named:
        module, _, attr = dotted.rpartition(".")
        try:
            getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError):
            bad.append(f"{dotted} ({where})")
    assert not bad, bad
