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
    "slider laid along the wrong side of the leg": ((('alpha = "90*deg"', 'alpha = "-90*deg"'),),
                                                    ["the loops do not close at the assembly pose [0.0, 0.0, 0.0]", "[assembly]"]),
    # item 2: plausibility of the values as written
    "base radius written in mm": (((' = "200*mm"', " = 250"),), ["lengths.Rb = 250", "below 10 m", "did you mean '250*mm'?"]),
    "length expression beyond 10 m": (((' = "200*mm"', ' = "250*1000*mm"'),), ["lengths.Rb = '250*1000*mm'", "below 10 m", "max_length"]),
    "DH length entry in mm": (((' = "rp"\ntheta = "-(90', ' = 50\ntheta = "-(90'),), ["frame 'P1'.d = 50", "did you mean '50*mm'?"]),
    "negative platform radius": (((' = "50*mm"', ' = "-50*mm"'),), ["lengths.rp = '-50*mm'", "non-negative length", "negative_lengths"]),
    "frame angle in degrees": ((('gamma = "210*deg"', "gamma = 210"),), ["frame 'A2'.gamma = 210", "did you mean '210*deg'?"]),
    "twist angle in degrees": ((('alpha = "90*deg"', "alpha = 90"),), ["frame 'L1'.alpha = 90", "did you mean '90*deg'?"]),
    "angle parameter in degrees": ((('offset = "40*deg"', "offset = 40"),), ["angles.offset = 40", "did you mean '40*deg'?"]),
    "workspace angle bound in degrees": ((('high = "10*deg"', "high = 10"),), ["coordinate phi.high = 10", "did you mean '10*deg'?"]),
    "workspace length bound in mm": ((('low = "-30*mm"', "low = -30"),), ["coordinate x.low = -30", "did you mean '-30*mm'?"]),
    "assembly stroke in mm": ((("l1 = 0.165", "l1 = 165"),), ["assembly.joints.l1 = 165", "did you mean '165*mm'?"]),
    "assembly joint angle in degrees": ((("{ a1 = 2.95", "{ a1 = 169"),), ["assembly.joints.a1 = 169", "did you mean '169*deg'?"]),
    "assembly pose in mm": ((("pose = [0.0, 0.0, 0.0]", "pose = [0.0, 20, 0.0]"),), ["assembly.pose (y) = 20", "did you mean '20*mm'?"]),
    "orientation angle in degrees": ((('orientation = [["z", "phi"]]', 'orientation = [["z", "phi"], ["z", 180]]'),),
                                     ["end_effector.orientation[1] = 180", "did you mean '180*deg'?"]),
    "angle coordinate without orientation": ((('orientation = [["z", "phi"]]', ""),),
                                             ["coordinate 'phi' = 'phi'", "end_effector.orientation", "moves nothing"]),
    "z coordinate in a planar mechanism": ((('{ name = "y", axis = "y"', '{ name = "y", axis = "z"'),),
                                           ["coordinate 'y'.axis = 'z'", "planar mechanism"]),
    "two coordinates on one axis": ((('{ name = "y", axis = "y"', '{ name = "y", axis = "x"'),),
                                    ["coordinate 'y'.axis = 'x'", "'x' is already x"]),
    "out-of-plane orientation in a planar mechanism": ((('orientation = [["z", "phi"]]', 'orientation = [["x", "phi"]]'),),
                                                       ["end_effector.orientation = ['x', 'phi']", "about z only"]),
    "stroke limits in mm written as metres": ((("[lengths]", '[limits]\nl1 = [140, 170]\n\n[lengths]'),),
                                              ["limits.l1 = 140", "did you mean '140*mm'?"]),
    "joint limits in degrees written as radians": ((("[lengths]", "[limits]\na1 = [-170, 170]\n\n[lengths]"),),
                                                   ["limits.a1 = -170", "did you mean '-170*deg'?"]),
    # joint and stroke limits (declared with issue 23's [limits]): the task box must stay within them
    "task box beyond the real strokes": ((("[lengths]", '[limits]\nl1 = ["140*mm", "170*mm"]\n\n[lengths]'),),
                                         ["the pose [", "(x, y, phi, SI) needs joint l1 = 0.183093", "outside its limits [0.14, 0.17]"]),
    "assembly outside the stroke limits": ((("[lengths]", '[limits]\nl1 = ["170*mm", "200*mm"]\n\n[lengths]'),),
                                           ["the assembly pose [0.0, 0.0, 0.0]", "needs joint l1 = 0.164861", "[0.17, 0.2]"]),
    "limits for a joint that does not exist": ((("[lengths]", '[limits]\nl9 = ["140*mm", "170*mm"]\n\n[lengths]'),),
                                               ["limits.l9", "a joint variable", "'l1'"]),
    "[checks] key typo": ((("[lengths]", "[checks]\nmax_lenght = 20\n\n[lengths]"),), ["checks.max_lenght = 20", "'max_length'"]),
    "[checks] negative_lengths names no length": ((("[lengths]", '[checks]\nnegative_lengths = ["Rc"]\n\n[lengths]'),),
                                                  ["checks.negative_lengths = ['Rc']", "names of [lengths]", "'Rb'"]),
    "[checks] max_length not positive": ((("[lengths]", "[checks]\nmax_length = 0\n\n[lengths]"),),
                                         ["checks.max_length = 0", "a positive length"]),
}


@pytest.mark.parametrize("case", list(MECHANISM_CASES))
def test_mechanism_file_mistake(case, tmp_path, capsys):
    edits, names = MECHANISM_CASES[case]
    code, out, err = _check(["check-mechanism", str(_edited(tmp_path, edits)), "--poses", "20"], capsys)
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


@pytest.mark.parametrize("edits, before, after", [
    # a large machine: [checks] max_length lifts the 10 m bound (the assembly check still runs)
    ([(' = "200*mm"', " = 250"), ("[lengths]", "[checks]\nmax_length = 300\n\n[lengths]")],
     "lengths.Rb = 250", "assembly.joints.l1 = 0.165 m was declared, but Newton closed the loops at l1 = 249.962"),
    # an intended negative length: listed in [checks] negative_lengths (the mirrored platform then
    # does not close near the declared joints)
    ([(' = "50*mm"', ' = "-50*mm"'), ("[lengths]", '[checks]\nnegative_lengths = ["rp"]\n\n[lengths]')],
     "lengths.rp", "assembly.joints.l1 = 0.165 m was declared, but Newton closed the loops at l1 = 0.24046"),
])
def test_declared_intent_lifts_a_plausibility_check(edits, before, after, tmp_path, capsys):
    """The override is read: the message moves from the plausibility check to the next check."""
    code, _, err = _check(["check-mechanism", str(_edited(tmp_path, edits[:1])), "--poses", "3"], capsys)
    assert code == 2 and before in err
    code, _, err = _check(["check-mechanism", str(_edited(tmp_path, edits)), "--poses", "3"], capsys)
    assert code == 2 and before not in err and after in err, err


def test_angles_written_with_a_unit_are_taken_as_meant(tmp_path, capsys):
    """'720*deg' and '4*pi' are beyond 2 pi but written with a unit: no plausibility error (the
    frame is the same as with 0 deg, so the file still checks clean)."""
    f = _edited(tmp_path, [('gamma = "210*deg"', 'gamma = "210*deg + 720*deg"'), ('gamma = "330*deg"', 'gamma = "330*deg + 4*pi"')])
    code, out, err = _check(["check-mechanism", str(f), "--poses", "3"], capsys)
    assert code == 0, err


# --- issue 27 item 6: the wrong kind of file is named as such ---------------------------------
STUDY = Path(__file__).resolve().parents[1] / "reports" / "studies" / "ucr3_example.toml"


def _study_naming(d: Path, target: Path) -> str:
    f = d / "s.toml"
    f.write_text(STUDY.read_text().replace('model = "ucr3"', f'mechanism = "{target}"').replace('variant = "verified"', ""))
    return str(f)


WRONG_KIND_CASES = {   # argv builder (tmp_path -> argv), strings of the one-line message
    "check-mechanism given a study file": (lambda d: ["check-mechanism", str(STUDY)],
                                           [f"mechanism file = '{STUDY}'", "this is a study file", f"evotol run {STUDY}"]),
    "run given a mechanism file": (lambda d: ["run", str(RPR), "--out", str(d)],
                                   [f"study file = '{RPR}'", "this is a mechanism description", "evotol check-mechanism",
                                    "[robot] mechanism ="]),
    "describe given a study file": (lambda d: ["describe", str(STUDY)], ["mechanism file", "this is a study file"]),
    "a study's [robot] mechanism is a study file": (lambda d: ["run", _study_naming(d, STUDY), "--out", str(d)],
                                                    [f"mechanism file = '{STUDY}'", "this is a study file"]),
    "describe --set for a description": (lambda d: ["describe", "ur5", "--set", "variant=paper"],
                                         ["--set = ['variant=paper']", "nothing for a mechanism description"]),
    "describe an unknown name lists the shipped descriptions": (lambda d: ["describe", "planar3rr"],
                                                                ["robot.model = 'planar3rr'", "'planar3rpr'", "description file"]),
}


@pytest.mark.parametrize("case", list(WRONG_KIND_CASES))
def test_wrong_kind_of_file(case, tmp_path, capsys):
    build, names = WRONG_KIND_CASES[case]
    code, out, err = _check(build(tmp_path), capsys)
    assert code == 2, (out, err)
    assert "Traceback" not in err
    message = err.strip().splitlines()[-1]
    for name in names:
        assert name in message, (name, message)


def test_describe_takes_shipped_mechanisms_and_description_files(tmp_path, capsys):
    """The 3-RPR's five sources by name and from a copy of its file; the UR5 by name."""
    f = tmp_path / "mine.toml"
    f.write_text(RPR.read_text())
    for target in ("planar3rpr", str(f)):
        code, out, err = _check(["describe", target], capsys)
        assert code == 0, err
        rows = [line.split()[:3] for line in out.splitlines() if line.startswith("  ") and len(line.split()) > 3]
        assert rows[1:6] == [["Rb", "length", "m"], ["rp", "length", "m"], ["l1", "actuator", "m"],
                             ["l2", "actuator", "m"], ["l3", "actuator", "m"]], out
    code, out, err = _check(["describe", "ur5", "--json"], capsys)
    import json
    assert code == 0 and json.loads(out)["robot"] == "UR5"


@pytest.mark.parametrize("table", [{}, {"sources": ["L*"]}])
def test_robot_table_without_mechanism_or_urdf_names_the_field(table):
    """A ``[robot]`` table given to ``model_from_table`` with neither ``mechanism`` nor ``urdf``
    is a one-line ValidationError naming ``robot.mechanism`` (value None) and saying what is
    expected -- not a bare KeyError."""
    from evotol.errors import ValidationError
    from evotol.robots.mechanism.model.error_model import model_from_table

    with pytest.raises(ValidationError) as exc:
        model_from_table(table)
    assert exc.value.field == "robot.mechanism" and exc.value.value is None
    assert "mechanism = \"file.toml\"" in exc.value.expected and "urdf = \"arm.urdf\"" in exc.value.expected
    assert len(str(exc.value).splitlines()) == 1


def test_a_serial_arm_out_of_reach_is_told_so_in_serial_words(tmp_path, capsys):
    """Issue 39: a serial arm (no loops) whose assembly pose is beyond its reach heard "the loops do not
    close". The PUMA 560 (reach about 0.86 m) asked for x = 1.4 m: the message says the arm does not reach."""
    src = (Path(__file__).resolve().parents[1] / "robots" / "mechanisms" / "puma560.toml").read_text(encoding="utf-8")
    far = src.replace('high = "700*mm"', 'high = "1500*mm"').replace(
        'pose = ["596.3*mm", "-150.05*mm", "-14.4*mm"]', 'pose = ["1400*mm", "-150.05*mm", "-14.4*mm"]')
    assert far != src
    f = tmp_path / "puma_far.toml"
    f.write_text(far, encoding="utf-8")
    from evotol.cli import main

    assert main(["check-mechanism", str(f)]) == 2
    err = capsys.readouterr().err
    assert "the arm does not reach the assembly pose [1.4" in err and "loops" not in err
