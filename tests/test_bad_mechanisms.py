"""Issue 27: a mechanism file that does not mean what was written is an error (or a warning)
naming the field, the value and the expectation -- before any computation.

Each case edits the second tutorial's description (``robots/mechanisms/planar3rpr.toml``, a
planar 3-RPR that checks clean) by text replacement and runs ``evotol check-mechanism`` on it:
exit code 2, no traceback, and the one-line message (the last line of stderr) names what it
must. The edits are the mistakes a new user made (issue 27's list).
"""
from __future__ import annotations

from pathlib import Path

import pytest

from evotol.cli import main

RPR = Path(__file__).resolve().parents[1] / "robots" / "mechanisms" / "planar3rpr.toml"
ASSEMBLY = ("[assembly]            # at the centre: strokes 164.9 mm, legs at 2.95 rad from the base radius\n"
            "pose = [0.0, 0.0, 0.0]\n")
JOINTS = "joints = { a1 = 2.95, l1 = 0.165, c1 = -0.68, a2 = 2.95, l2 = 0.165, c2 = -0.68, a3 = 2.95, l3 = 0.165, c3 = -0.68 }\n"


def _edited(tmp_path: Path, edits) -> Path:
    text = RPR.read_text()
    for old, new in edits:
        assert old in text, old             # the case must edit something real
        text = text.replace(old, new, 1)
    f = tmp_path / "mine.toml"
    f.write_text(text)
    return f


def _check(argv, capsys) -> tuple[int, str, str]:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    cap = capsys.readouterr()
    return code, cap.out, cap.err


# name: (text edits, strings the one-line message must contain)
MECHANISM_CASES = {
    # item 1: the declared assembly is the assembly
    "no [assembly] table": (((ASSEMBLY + JOINTS, ""),), ["assembly = None", "closed-loop", "a1, l1, c1"]),
    "[assembly] without joints": (((JOINTS, ""),), ["assembly = None", "closed-loop"]),
    "assembly joints incomplete": (((", c3 = -0.68 }", " }"),), ["assembly.joints", "missing: c3"]),
    "loop closed to the wrong frame": ((('frames = ["P2", "P1"]', 'frames = ["P2", "C1"]'),),
                                       ["assembly.joints.c2 = -0.68 rad", "c2 = -2.13", "loop residual at the declared joints is 0.0372 m"]),
    "base radius 2.5 m (meant dm)": (((' = "200*mm"', " = 2.5"),), ["assembly.joints.a1 = 2.95 rad", "a1 = 6.27", "3.45 m"]),
    "declared stroke far from the closed one": ((("l1 = 0.165", "l1 = 0.3"),),
                                                ["assembly.joints.l1 = 0.3 m", "l1 = 0.164861 m", "more than 0.04 m away"]),
    "declared leg angle far from the closed one": ((("{ a1 = 2.95", "{ a1 = 1.95"),),
                                                   ["assembly.joints.a1 = 1.95 rad", "a1 = 2.94539", "more than 0.5 rad"]),
    "declared platform joint of the other side": ((("c1 = -0.68", "c1 = 0.68"),), ["assembly.joints.c1 = 0.68 rad", "loop residual"]),
}


@pytest.mark.parametrize("case", list(MECHANISM_CASES))
def test_mechanism_file_mistake(case, tmp_path, capsys):
    edits, names = MECHANISM_CASES[case]
    code, out, err = _check(["check-mechanism", str(_edited(tmp_path, edits)), "--poses", "3"], capsys)
    assert code == 2, (out, err)
    assert "Traceback" not in err
    message = err.strip().splitlines()[-1]
    assert message.startswith("evotol: error: "), message
    for name in names:
        assert name in message, (name, message)


def test_the_unedited_tutorial_file_checks_clean(tmp_path, capsys):
    """The table's base file passes, so every failure above is the edit's."""
    code, out, err = _check(["check-mechanism", str(_edited(tmp_path, ())), "--poses", "3"], capsys)
    assert code == 0 and not err.strip(), err
