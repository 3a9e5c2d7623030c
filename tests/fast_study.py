"""A fast user study for CLI tests (test helper, not a test): the shipped UCR3 example study file
cut to 8 poses, the sensitivity method only and 20 Monte Carlo samples (about 2 s)."""
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ucr3_example.toml"
FAST = (("grid = [5, 5, 3]", "grid = [2, 2, 2]"), ("n_samples = 500", "n_samples = 20"), ("optimum = {}\n", ""),
        ("ga = { pop_size = 60, n_gen = 60 }\n", ""), ("nsga2 = { pop_size = 60, n_gen = 60 }\n", ""))


def fast_study(folder: Path, *edits, fast=FAST) -> Path:
    """The example study with ``fast`` and ``edits`` (old, new) applied (each must match), written
    to ``folder/study.toml``."""
    text = EXAMPLE.read_text()
    for old, new in tuple(fast) + tuple(edits):
        assert old in text, old
        text = text.replace(old, new)
    folder.mkdir(parents=True, exist_ok=True)
    f = folder / "study.toml"
    f.write_text(text)
    return f
