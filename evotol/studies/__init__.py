"""Reproducible studies, discovered automatically.

Every module in this package that defines ``STUDY = Study(...)`` is a study that
``evotol reproduce NAME --out DIR`` runs. A study's ``run(out_dir, quick=False, seed=0)`` writes
``out_dir/NAME.html`` and ``out_dir/NAME.json`` and returns the JSON summary as a dict.
``quick=True`` asks for a smaller run (used by tests); the full run is the default.
"""
from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from evotol.errors import ValidationError


@dataclass(frozen=True)
class Study:
    name: str
    title: str
    run: Callable[..., dict]
    seed_paper: str = ""


def available() -> dict[str, Study]:
    """All studies, by name, in name order."""
    found = {}
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        study = getattr(mod, "STUDY", None)
        if isinstance(study, Study):
            found[study.name] = study
    return dict(sorted(found.items()))


def get(name: str) -> Study:
    studies = available()
    if name not in studies:
        raise ValidationError("study", name, f"one of {sorted(studies)} or 'all'")
    return studies[name]
