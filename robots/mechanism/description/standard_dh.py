"""Standard (distal) Denavit-Hartenberg descriptions: a textbook's table read as it is printed.

A description with ``convention = "standard"`` gives one ``[[frame]]`` row per link with the
textbook's four entries (Spong, Hutchinson & Vidyasagar, *Robot Modeling and Control*, eq. 3.10;
Corke, *Robotics, Vision and Control*, sec. 7.1.1): the link transform is

    A_i = Rot(z, theta_i) Trans(z, d_i) Trans(x, a_i) Rot(x, alpha_i)

and the arm is ``T = B A_1 A_2 ... A_n E`` with the fixed base ``B`` (``[base]``, before the first
row) and tool ``E`` (``[tool]``, after the last) given the same way (``a``, ``alpha``, ``d``,
``theta``; missing entries are 0). A revolute row holds its joint variable in ``theta`` (the
variable plus a constant offset: ``"q2"``, ``"q2 - pi/2"``; ``theta`` omitted: ``q<i>``), a
prismatic row in ``d`` (``"q3"``, ``"q3 + 0.1"``). Every other entry is a constant (SI, or an
expression such as ``"431.8*mm"``, ``"pi/2"``).

**Sources** are named after the textbook's parameters: ``a2``, ``alpha3``, ``d4``, ``theta6`` (for a
revolute row the joint offset, i.e. the encoder zero; for a prismatic row ``d<i>`` is the stroke
offset), and ``base.a``, ``base.alpha``, ``base.d``, ``base.theta``, ``tool.d``, ... for the base and
tool. Without ``[tolerances] sources`` every one of them is a source. The row index ``i`` counts
from 1; a row may have a ``name`` (the name of its distal frame ``i``, default ``"<i>"``).

**How it is computed.** The table is rewritten, exactly, in the modified (Khalil-Kleinfinger)
convention the rest of :mod:`evotol.robots.mechanism` uses (``Rot(z, gamma) Trans(z, b) Rot(x, alpha)
Trans(x, d) Rot(z, theta) Trans(z, r)``, :mod:`evotol.robots.mechanism.kinematics.tree`):

* joint frame ``J<i>`` (on joint ``i``'s axis) from distal frame ``i-1``: ``theta = theta_i``,
  ``r = d_i`` (``Rot(z, theta_i) Trans(z, d_i)``);
* distal frame ``i`` (fixed) from ``J<i>``: ``alpha = alpha_i``, ``d = a_i`` (``Trans(x, a_i)`` and
  ``Rot(x, alpha_i)`` commute);
* the base frame ``base`` (fixed, from the world ``"0"``): ``gamma = theta_B``, ``b = d_B``,
  ``alpha = alpha_B``, ``d = a_B``; the tool frame ``tool`` likewise from frame ``n``.

Each textbook entry is a design parameter of that description (``a2`` in ``[lengths]``,
``alpha3`` in ``[angles]``...; the base's and tool's as ``base_d``, ... with the source names
``base.d``, ... as aliases), so a tolerance on ``a2`` moves exactly the entry the textbook calls
``a2``. ``tests/test_standard_dh.py`` checks the forward kinematics against the textbook product of
``A_i`` to 1e-12 and the PUMA 560 described both ways (``robots/mechanisms/puma560.toml`` and
``puma560_modified.toml``).
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import check_table_keys
from evotol.robots.mechanism.description.expressions import CONSTANTS, FUNCTIONS, Expression
from evotol.robots.mechanism.description.plausibility import MAX_LENGTH, _check_angle, _check_length, _constant

#: entries of a standard-DH row, of ``[base]`` and of ``[tool]``
STANDARD_FIELDS = ("a", "alpha", "d", "theta")
ROW_KEYS = ("name", "joint", "actuated", "description") + STANDARD_FIELDS
#: keys of a modified-DH row that a standard row must not have
MODIFIED_ONLY = ("gamma", "b", "r", "antecedent")
CONVENTIONS = ("modified", "standard")
#: the keys a standard description has instead of (or next to) a modified one's
STANDARD_TOP_KEYS = ("convention", "base", "tool")


def convention_of(spec: Mapping) -> str:
    """The DH convention a description declares: ``"modified"`` (default) or ``"standard"``.

    Parameters
    ----------
    spec : Mapping
        The parsed description.

    Returns
    -------
    str
        ``"modified"`` or ``"standard"``.

    Raises
    ------
    evotol.errors.ValidationError
        Another ``convention``, or ``[base]``/``[tool]`` tables in a modified description.
    """
    conv = spec.get("convention", "modified")
    if conv not in CONVENTIONS:
        raise ValidationError("convention", conv, "'standard' (a, alpha, d, theta: Spong/Corke) or 'modified' "
                                                  "(Khalil-Kleinfinger, the default)")
    if conv == "modified":
        for k in ("base", "tool"):
            if k in spec:
                raise ValidationError(k, spec[k], "convention = \"standard\" for a [base]/[tool] table of a, alpha, d, "
                                                  "theta (a modified description gives them as fixed [[frame]] rows)")
    return conv


def _row_values(row: Mapping, where: str, max_length: float) -> dict:
    """The written entries of one row (or base/tool table), checked: constants, plausible units."""
    out = {}
    for k in STANDARD_FIELDS:
        if k not in row:
            continue
        raw = row[k]
        Expression.parse(raw, f"{where}.{k}")
        if k in ("a", "d"):
            _check_length(f"{where}.{k}", raw, _constant(raw, f"{where}.{k}"), max_length)
        else:
            _check_angle(f"{where}.{k}", raw)
        out[k] = raw
    return out


def _fixed_table(table, where: str, max_length: float) -> dict:
    if not isinstance(table, Mapping):
        raise ValidationError(where, table, "a table with a, alpha, d, theta (constants, SI)")
    bad = [k for k in table if k in MODIFIED_ONLY]
    if bad:
        raise ValidationError(f"{where}.{bad[0]}", table[bad[0]], "a standard-DH entry a, alpha, d or theta "
                                                                   "(gamma, b, r belong to the modified convention)")
    check_table_keys(table, STANDARD_FIELDS, where)
    vals = _row_values(table, where, max_length)
    for k, raw in vals.items():
        e = Expression.parse(raw, f"{where}.{k}")
        if not e.is_constant:
            raise ValidationError(f"{where}.{k}", raw, "a constant (the base and tool do not move)")
    return vals


def _joint_entry(raw, where: str, joint: str, default_var: str) -> tuple[str, object]:
    """(joint variable, constant offset as written or computed) of a joint entry ``q + c``."""
    if raw is None:
        return default_var, 0.0
    e = Expression.parse(raw, where)
    if len(e.names) != 1:
        raise ValidationError(where, raw, f"the {joint} joint's variable plus a constant, e.g. 'q2' or 'q2 - pi/2' "
                                          f"({'no' if not e.names else 'several'} variables found)")
    var = next(iter(e.names))
    v0 = complex(e({var: 0.0})).real
    v1 = complex(e({var: 1.0})).real
    v2 = complex(e({var: 2.5})).real
    if not (np.isclose(v1 - v0, 1.0, rtol=0, atol=1e-12) and np.isclose(v2 - v0, 2.5, rtol=0, atol=1e-12)):
        raise ValidationError(where, raw, "the joint variable plus a constant offset (slope 1), e.g. 'q2 - pi/2'")
    return var, float(v0)


def standard_to_modified(spec: Mapping) -> tuple[dict, dict]:
    """Rewrite a standard-DH description as the modified-DH description evotol computes with.

    Parameters
    ----------
    spec : Mapping
        The parsed description with ``convention = "standard"``: ``[[frame]]`` rows with ``a``,
        ``alpha``, ``d``, ``theta`` (SI or expressions), ``joint`` (``"revolute"`` default, or
        ``"prismatic"``), optional ``name``, ``actuated`` (default true) and ``description``;
        optional ``[base]`` and ``[tool]`` tables of the same entries; the other tables as in a
        modified description (``end_effector``, ``assembly``, ``limits``, ``tolerances``...).

    Returns
    -------
    spec : dict
        The equivalent modified description (frames ``base``, ``J1``, ``1``, ..., ``Jn``, ``n``,
        ``tool``; ``[lengths]``/``[angles]`` holding one parameter per textbook entry; the default
        sources every textbook entry; ``end_effector.frame`` the tool, else the last row, unless
        given).
    aliases : dict of str to str
        Source name -> parameter name for the base and tool entries (``"base.d" -> "base_d"``).

    Raises
    ------
    evotol.errors.ValidationError
        No rows; a row with a modified-DH key (``gamma``, ``b``, ``r``, ``antecedent``) or an
        unknown key; a joint entry that is not a variable plus a constant; a constant entry that
        uses a name; ``[lengths]``/``[angles]`` tables next to standard rows; a joint variable
        named like a textbook entry (``theta1``); two rows with one joint variable.
    """
    rows = spec.get("frame")
    if not isinstance(rows, list) or not rows:
        raise ValidationError("frame", rows, "a list of [[frame]] rows with a, alpha, d, theta (the standard-DH table)")
    for k in ("lengths", "angles"):
        if k in spec:
            raise ValidationError(k, spec[k], "no [lengths]/[angles] in a standard description: write the values in "
                                              "the rows (the sources are named after them: a2, alpha3, d4, theta6)")
    if "urdf" in spec:
        raise ValidationError("convention", "standard", "no urdf next to a standard-DH table")
    checks = spec.get("checks", {})
    max_length = _constant(checks.get("max_length", MAX_LENGTH), "checks.max_length") if isinstance(checks, Mapping) else None
    max_length = MAX_LENGTH if max_length is None else max_length
    lengths, angles, frames, sources, aliases, variables = {}, {}, [], [], {}, {}
    written = {}

    def param(name: str, field: str, raw, where: str):
        e = Expression.parse(raw, where)
        if not e.is_constant:
            raise ValidationError(where, raw, f"a constant (names {sorted(e.names)} are not joint entries here)")
        (lengths if field in ("a", "d") else angles)[name] = raw if not isinstance(raw, str) else float(e({}))
        written[name] = where
        sources.append(name)
        return name

    prev = "0"
    if "base" in spec:
        vals = _fixed_table(spec["base"], "base", max_length)
        kk = {}
        for k, kf in (("theta", "gamma"), ("d", "b"), ("alpha", "alpha"), ("a", "d")):
            p = param(f"base_{k}", k, vals.get(k, 0.0), f"base.{k}")
            aliases[f"base.{k}"] = p
            kk[kf] = p
        frames.append({"name": "base", "antecedent": "0", "joint": "fixed", "description": "standard-DH base B", **kk})
        prev = "base"
    names = []
    for i, row in enumerate(rows, start=1):
        where = f"frame[{i - 1}]"
        if not isinstance(row, Mapping):
            raise ValidationError(where, row, "a table with a, alpha, d, theta")
        bad = [k for k in row if k in MODIFIED_ONLY]
        if bad:
            raise ValidationError(f"{where}.{bad[0]}", row[bad[0]], "a standard-DH entry a, alpha, d or theta (gamma, b, r, "
                                                                     "antecedent belong to convention = \"modified\")")
        check_table_keys(row, ROW_KEYS, where)
        joint = row.get("joint", "revolute")
        if joint not in ("revolute", "prismatic"):
            raise ValidationError(f"{where}.joint", joint, "'revolute' (variable in theta) or 'prismatic' (variable in d); "
                                                           "a fixed offset belongs in [base], [tool] or a neighbouring row")
        vals = _row_values(row, where, max_length)
        name = str(row.get("name", i))
        if not name or "." in name or name in ("0", "base", "tool") or name in names or name.startswith("J"):
            raise ValidationError(f"{where}.name", name, "a unique frame name without '.', not '0', 'base', 'tool' or 'J...'")
        names.append(name)
        jvar_field = "theta" if joint == "revolute" else "d"
        var, offset = _joint_entry(vals.get(jvar_field), f"{where}.{jvar_field}", joint, f"q{i}")
        if var in variables:
            raise ValidationError(f"{where}.{jvar_field}", vals.get(jvar_field), f"a joint variable of its own ({var} is "
                                                                                  f"already row {variables[var]}'s)")
        variables[var] = i
        for k in STANDARD_FIELDS:
            if k == jvar_field:
                p = param(f"{k}{i}", k, offset, f"{where}.{k}")
            else:
                p = param(f"{k}{i}", k, vals.get(k, 0.0), f"{where}.{k}")
        jv = {"theta": f"{var} + theta{i}", "r": f"d{i}"} if joint == "revolute" else {"theta": f"theta{i}", "r": f"{var} + d{i}"}
        frames.append({"name": f"J{i}", "antecedent": prev, "joint": joint, "actuated": bool(row.get("actuated", True)),
                       "description": f"joint {i} ({joint}, standard-DH row {i}: Rot(z, theta{i}) Trans(z, d{i}))", **jv})
        frames.append({"name": name, "antecedent": f"J{i}", "joint": "fixed", "alpha": f"alpha{i}", "d": f"a{i}",
                       "description": row.get("description", f"standard-DH frame {i}: Trans(x, a{i}) Rot(x, alpha{i})")})
        prev = name
    if "tool" in spec:
        vals = _fixed_table(spec["tool"], "tool", max_length)
        kk = {}
        for k, kf in (("theta", "gamma"), ("d", "b"), ("alpha", "alpha"), ("a", "d")):
            p = param(f"tool_{k}", k, vals.get(k, 0.0), f"tool.{k}")
            aliases[f"tool.{k}"] = p
            kk[kf] = p
        frames.append({"name": "tool", "antecedent": prev, "joint": "fixed", "description": "standard-DH tool E", **kk})
        prev = "tool"
    clash = sorted(set(variables) & (set(lengths) | set(angles) | set(CONSTANTS) | set(FUNCTIONS)))
    if clash:
        i = variables[clash[0]]
        raise ValidationError(f"frame[{i - 1}]", clash[0], f"a joint variable not named like a textbook entry or constant "
                                                           f"({clash[0]!r} is a source name here): e.g. 'q{i}'")
    out = {k: v for k, v in spec.items() if k not in ("convention", "base", "tool", "frame")}
    out["frame"] = frames
    out["lengths"], out["angles"] = lengths, angles
    ee = dict(out.get("end_effector", {}))
    ee.setdefault("frame", prev)
    out["end_effector"] = ee
    tol = dict(out.get("tolerances", {}))
    tol.setdefault("sources", [a for s in sources for a in [next((k for k, v in aliases.items() if v == s), s)]])
    out["tolerances"] = tol
    chk = dict(checks) if isinstance(checks, Mapping) else checks
    if isinstance(chk, dict):       # a negative a_i or d_i is an ordinary standard-DH value, not a mirrored part
        chk["negative_lengths"] = sorted(set(chk.get("negative_lengths", [])) | set(lengths))
        out["checks"] = chk
    return out, aliases
