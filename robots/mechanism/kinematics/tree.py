"""Kinematics computed from a :class:`~evotol.robots.mechanism.description.mechanism.Mechanism`.

* **Forward kinematics** of the frame tree: ``^0T_j = ^0T_{a(j)} Rot(z,gamma) Trans(z,b) Rot(x,alpha)
  Trans(x,d) Rot(z,theta) Trans(z,r)`` (Khalil & Kleinfinger 1986), vectorised over poses.
* **First-order maps**: a change of any DH entry of frame ``j`` moves every frame downstream of
  ``j`` by the *spatial twist* of that elementary motion (``[omega; v_0]``, ``v_0`` the velocity of
  the point at the base origin): rotation about ``z_{a(j)}`` through ``O_{a(j)}`` for ``gamma``,
  translation along it for ``b``, rotation/translation along the intermediate ``x`` axis for
  ``alpha``/``d``, rotation/translation along ``z_j`` for ``theta``/``r``. A frame ``k`` then moves
  by ``[dp_k; dphi] = [v_0 + omega x p_k; omega]``. Derivatives of expression entries (``"q1 - pi"``,
  ``"-L0/2"``) come from the complex step, so every Jacobian here is exact to rounding --
  nothing is derived by hand.
* **Inverse geometry**: Gauss-Newton continued from the assembly configuration
  (:mod:`evotol.robots.mechanism.posture.inverse_geometry`, whose :class:`InverseGeometry
  <evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry>` :class:`Kinematics` inherits).

Twists here are ordered ``[translation; rotation]`` like :mod:`evotol.robots.base` (the clearance engine
uses the thesis's ``[rotation; translation]``).

The parameters several definitions of this module share are described once, here.

Parameters
----------
params : dict or None, optional
    Overrides of design parameters (scalars or (n,) arrays, m or rad).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evotol.errors import ValidationError
from evotol.robots.clearance.kinematics import DH_FIELDS, DHFrame, DHTree, inv_transform, rotation_vector
from evotol.robots.mechanism.posture import working_mode
from evotol.robots.mechanism.description.expressions import Expression
from evotol.robots.mechanism.posture.inverse_geometry import InverseGeometry
from evotol.robots.mechanism.description.limits import check_limit_names
from evotol.robots.mechanism.description.mechanism import Mechanism
from evotol.robots.mechanism.description.parts import AXES, joint_units
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS, placement_error, placement_twists
from evotol.robots.mechanism.kinematics.rotations import cross_rows, rot_z_inverse

IN_PLANE = (0, 1, 5)            # x, y, rotation about z
@dataclass
class State:
    """Kinematic state at ``n`` configurations: world transforms, entry derivatives, entry twists.

    Parameters
    ----------
    world : dict
        Frame or point name (``"0"``: the base) -> (n, 4, 4) transform in the base frame
        (position in m).
    grads : dict
        DH entry ``(frame, field)`` -> {name: (n,) derivative of the entry with respect to that
        name} for the names asked for (``wrt`` of :meth:`Kinematics.state`); m or rad per unit
        of the name.
    twists : dict
        DH entry ``(frame, field)`` (or placement error ``(frame, "shift_x")``...) -> (n, 6)
        spatial twist ``[omega; v0]`` of a unit change of it (rad and m per m or rad); empty when
        not computed.
    """

    n: int
    world: dict            # frame -> (n, 4, 4)
    grads: dict            # (frame, field) -> {name: (n,) d entry / d name}
    twists: dict           # (frame, field) -> (n, 6) spatial twist [omega; v0] of a unit change


class Kinematics(InverseGeometry):
    """Kinematics of a described mechanism (see the module docstring); the inverse geometry
    (:meth:`assembly`, :meth:`inverse_geometry`, :meth:`solve_passive`) is inherited from
    :class:`~evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry`.

    Parameters
    ----------
    mech : evotol.robots.mechanism.description.mechanism.Mechanism
        The description; its DH entries are parsed here and its joint variables (names in the
        entries that are not design parameters) found.

    Raises
    ------
    evotol.errors.ValidationError
        A DH entry that uses a pose coordinate, a name that is neither a parameter nor a joint
        variable (a name in the ``theta`` of a revolute / ``r`` of a prismatic frame), an actuated
        joint whose entry has not exactly one joint variable, an orientation entry with an
        unknown name, a loop whose two frames are on one branch, a loop group without an
        actuated joint, a ``[limits]`` key that is not a joint variable, or a closed-loop
        mechanism without a usable ``[assembly]`` (:mod:`evotol.robots.mechanism.posture.working_mode`).
    """

    def __init__(self, mech: Mechanism):
        self.mech = mech
        self.tree = DHTree([DHFrame(f.name, f.antecedent, sigma=f.sigma, mu=int(f.actuated)) for f in mech.frames])
        self.order = self.tree.order
        self.paths = {k: set(self.tree.path(k)) for k in self.tree.frames}
        self.paths["0"] = set()
        # points: mean of frame origins, oriented like their first frame (parts.Point)
        self.points = {p.name: p.frames for p in mech.points}
        for p, frs in self.points.items():
            self.paths[p] = set().union(*(self.paths[f] for f in frs))
        self.expr = {}
        used = []
        for f in mech.frames:
            for k in DH_FIELDS:
                e = Expression.parse(getattr(f, k), f"frame {f.name!r}.{k}")
                self.expr[(f.name, k)] = e
                used += [x for x in sorted(e.names) if x not in used]
        params = mech.parameters
        coords = {c.name for c in mech.coordinates}
        bad = [x for x in used if x in coords]
        if bad:
            raise ValidationError("DH entry name", bad[0], "a parameter or a joint variable (pose coordinates may only "
                                                            "appear in end_effector.orientation)")
        self.variables = [x for x in used if x not in params]
        in_joint = {x for f in mech.frames if f.joint_field for x in self.expr[(f.name, f.joint_field)].names}
        for x in self.variables:
            if x not in in_joint:
                raise ValidationError("DH entry name", x, f"a parameter ({sorted(params)}) or a joint variable "
                                                          "(a name in the theta of a revolute / r of a prismatic frame)")
        self.actuated = []
        for f in mech.frames:
            if f.actuated:
                vs = [x for x in self.expr[(f.name, f.joint_field)].names if x in self.variables]
                if len(vs) != 1:
                    raise ValidationError(f"frame {f.name!r}.{f.joint_field}", getattr(f, f.joint_field),
                                          "exactly one joint variable for an actuated joint")
                if vs[0] not in self.actuated:
                    self.actuated.append(vs[0])
        self.passive = [x for x in self.variables if x not in self.actuated]
        self.uses = {}
        for (fr, k), e in self.expr.items():
            for x in e.names:
                self.uses.setdefault(x, []).append((fr, k))
        self.orientation = [(ax, Expression.parse(t, "end_effector.orientation")) for ax, t in mech.orientation]
        for _, e in self.orientation:
            unknown = e.names - coords - set(params)
            if unknown:
                raise ValidationError("end_effector.orientation", sorted(unknown)[0], f"pose coordinates {sorted(coords)} or parameters")
        lengths = [abs(v) for v in mech.lengths.values() if v != 0]
        self.length_scale = float(max(lengths)) if lengths else 1.0
        self.coord_axes = [(i, AXES.index(c.axis)) for i, c in enumerate(mech.coordinates) if c.axis in AXES]
        self._check_loops_actuated()
        check_limit_names(mech.limits, self.variables)
        self.joint_unit = {x: u for x, u in joint_units(mech.frames, set(params)).items() if x in self.variables}
        working_mode.check_declared(self)           # a closed-loop mechanism declares its assembly (issue 27)
        self._assembly = None
        self._cache = {}

    # ------------------------------------------------------------------ structure checks
    def _cycle(self, lp) -> set:
        a, b = self.paths[lp.a], self.paths[lp.b]
        return a ^ b

    def _check_loops_actuated(self) -> None:
        """Every group of loops that share frames must contain an actuated joint (else it cannot be driven)."""
        loops = list(self.mech.loops)
        if not loops:
            return
        cycles = [self._cycle(lp) for lp in loops]
        for lp, c in zip(loops, cycles):
            if not c:
                raise ValidationError(f"loop {lp.a}-{lp.b}", (lp.a, lp.b), "two frames on different branches of the tree (a cut joint)")
        group = list(range(len(loops)))

        def root(i):
            while group[i] != i:
                i = group[i]
            return i

        for i in range(len(loops)):
            for j in range(i):
                if cycles[i] & cycles[j]:
                    group[root(i)] = root(j)
        act = {f.name for f in self.mech.frames if f.actuated}
        coupled = {fr for x in self.actuated for fr, k in self.uses.get(x, [])}
        for r in {root(i) for i in range(len(loops))}:
            frames = set().union(*(cycles[i] for i in range(len(loops)) if root(i) == r))
            if not frames & (act | coupled):
                lp = loops[r]
                raise ValidationError(f"loop {lp.a}-{lp.b}", sorted(frames), "a loop (or group of loops sharing links) with an actuated joint")

    # ------------------------------------------------------------------ forward kinematics
    def env(self, q: dict, n: int, params: dict | None = None) -> dict:
        """Values of every name the DH entries may use, for evaluating the expressions.

        Parameters
        ----------
        q : dict of str to float or (n,) ndarray
            Joint variable -> its value(s) (rad or m); every joint variable is required.

        Returns
        -------
        dict
            The design parameters (with the overrides) and the joint variables broadcast to (n,).

        Raises
        ------
        KeyError
            A joint variable missing from ``q``.
        """
        env = {k: v for k, v in self.mech.parameters.items()}
        if params:
            env.update(params)
        for x in self.variables:
            env[x] = np.broadcast_to(np.asarray(q[x], float), (n,))
        return env

    def state(self, q: dict, n: int, *, wrt=(), params: dict | None = None, offsets: dict | None = None,
              twists: bool = True, placement=()) -> State:
        """Evaluate the tree at ``n`` configurations. q: joint variables (n,) arrays; params:
        overrides of design parameters (scalars or (n,) arrays); offsets: additive errors of DH
        entries ``{(frame, field): (n,) array}`` and placement errors ``{(frame, "tilt_x"): ...}``
        (:mod:`evotol.robots.mechanism.kinematics.placement`); wrt: names whose derivatives are wanted; placement:
        frames whose placement twists are wanted (``twists[(frame, "shift_x")]`` ...).

        Parameters
        ----------
        q : dict of str to (n,) ndarray
            Every joint variable -> its values (rad or m).
        wrt : iterable of str, optional
            Names (joint variables or parameters) whose derivatives of the entries are wanted in
            ``State.grads``.
        offsets : dict or None, optional
            Additive errors ``{(frame, field): (n,) array}`` of DH entries (m or rad) and
            placement errors ``{(frame, "shift_x" ... "tilt_z"): (n,) array}`` (m, rad).
        twists : bool, optional
            Compute the spatial twists of the entries (needed by :meth:`frame_jacobian`);
            False: ``State.twists`` is empty (faster forward kinematics).
        placement : collection of str, optional
            Frames whose placement-error twists are also wanted.

        Returns
        -------
        State
            World transforms of every frame and point, the entry derivatives and twists.
        """
        env = self.env(q, n, params)
        world = {"0": np.broadcast_to(np.eye(4), (n, 4, 4))}
        grads, tw = {}, {}
        wrt = set(wrt)
        for fname in self.order:
            f = self.tree.frames[fname]
            vals = []
            for k in DH_FIELDS:
                e = self.expr[(fname, k)]
                if e.is_constant and not offsets:
                    v = float(e({}))
                elif wrt & e.names:
                    v, g = e.value_and_gradient(env, wrt)
                    grads[(fname, k)] = {x: np.broadcast_to(gx, (n,)) for x, gx in g.items()}
                else:
                    v = np.real(e(env)) if not e.is_constant else float(e({}))
                if offsets and (fname, k) in offsets:
                    v = v + offsets[(fname, k)]
                vals.append(np.broadcast_to(np.asarray(v, float), (n,)))
            Ta = world[f.antecedent]
            g_, b_, al, d_, th, r_ = vals
            # closed form of Rot(z,g) Trans(z,b) Rot(x,al) Trans(x,d) Rot(z,th) Trans(z,r)
            cg, sg, ca, sa, ct, st_ = np.cos(g_), np.sin(g_), np.cos(al), np.sin(al), np.cos(th), np.sin(th)
            R1 = np.empty((n, 3, 3))                      # Rot(z,g) Rot(x,al)
            R1[:, 0, 0], R1[:, 0, 1], R1[:, 0, 2] = cg, -sg * ca, sg * sa
            R1[:, 1, 0], R1[:, 1, 1], R1[:, 1, 2] = sg, cg * ca, -cg * sa
            R1[:, 2, 0], R1[:, 2, 1], R1[:, 2, 2] = 0.0, sa, ca
            L = np.zeros((n, 4, 4))
            L[:, :3, 0] = R1[:, :, 0] * ct[:, None] + R1[:, :, 1] * st_[:, None]
            L[:, :3, 1] = -R1[:, :, 0] * st_[:, None] + R1[:, :, 1] * ct[:, None]
            L[:, :3, 2] = R1[:, :, 2]
            p2 = np.stack([d_ * cg, d_ * sg, b_], axis=1)  # origin after Trans(x, d)
            L[:, :3, 3] = p2 + r_[:, None] * R1[:, :, 2]
            L[:, 3, 3] = 1.0
            E = None
            if offsets:
                perr = {k: offsets[(fname, k)] for k in PLACEMENT_FIELDS if (fname, k) in offsets}
                E = placement_error(perr, n) if perr else None
            fixed = f.sigma == 2
            if E is None:
                world[fname] = Ta @ L
            elif fixed:                                 # placement = the frame itself
                world[fname] = Ta @ L @ E
            else:                                       # placement = before Rot(z, theta) Trans(z, r)
                P = np.zeros((n, 4, 4))
                P[:, :3, :3], P[:, :3, 3], P[:, 3, 3] = R1, p2, 1.0
                world[fname] = Ta @ P @ E @ inv_transform(P) @ L
            if twists:
                Ra, pa = Ta[:, :3, :3], Ta[:, :3, 3]
                za = Ra[:, :, 2]
                x1 = Ra[:, :, 0] * cg[:, None] + Ra[:, :, 1] * sg[:, None]
                p1 = pa + za * b_[:, None]
                Tj = world[fname] if (E is None or not fixed) else world[fname] @ inv_transform(E)
                z2 = Tj[:, :3, 2]
                q2 = Tj[:, :3, 3] - r_[:, None] * z2      # origin after Trans(x, d), E included
                zero = np.zeros((n, 3))
                for k, (w, v) in zip(DH_FIELDS, ((za, cross_rows(pa, za)), (zero, za), (x1, cross_rows(p1, x1)),
                                                 (zero, x1), (z2, cross_rows(q2, z2)), (zero, z2))):
                    tw[(fname, k)] = np.concatenate([w, v], axis=1)
                if fname in placement:
                    if fixed:
                        Tp = world[fname]
                    else:
                        Tp = np.array(Tj)
                        Tp[:, :3, :3] = Tj[:, :3, :3] @ rot_z_inverse(th)
                        Tp[:, :3, 3] = q2
                    for k, t in placement_twists(Tp).items():
                        tw[(fname, k)] = t
        for p, frs in self.points.items():
            T = world[frs[0]].copy()
            T[:, :3, 3] = sum(world[f][:, :3, 3] for f in frs) / len(frs)
            world[p] = T
        return State(n, world, grads, tw)

    def frame_jacobian(self, st: State, frame: str, columns) -> np.ndarray:
        """Motion ``[dp_k; dphi]`` (n, 6, n_columns) of frame ``k`` per unit change of each column:
        a name (joint variable or parameter, through every entry that uses it) or a DH entry
        ``(frame, field)``. For a point: the mean of its frames' motions, the rotation of its first.

        Parameters
        ----------
        st : State
            State with twists (``twists=True``) and the derivatives with respect to the name
            columns (``wrt``).
        frame : str
            Frame or point ``k``.
        columns : sequence of str or (str, str)
            Each a name (joint variable or design parameter) or a DH entry / placement error
            ``(frame, field)``; a column that does not move ``k`` gives zeros.

        Returns
        -------
        (n, 6, len(columns)) ndarray
            ``[dp_k (m); dphi (rad)]`` in the base frame per unit change of each column (m or
            rad).
        """
        if frame in self.points:
            frs = self.points[frame]
            J = [self.frame_jacobian(st, f, columns) for f in frs]
            out = J[0].copy()
            out[:, :3] = sum(j[:, :3] for j in J) / len(J)
            return out
        path = self.paths[frame]
        n = st.n
        S = np.zeros((n, 6, len(columns)))          # spatial twists [omega; v0]
        for c, col in enumerate(columns):
            if isinstance(col, tuple):
                if col[0] in path:
                    S[:, :, c] += st.twists[col]
            else:
                for key in self.uses.get(col, ()):
                    if key[0] in path and key in st.grads and col in st.grads[key]:
                        S[:, :, c] += st.twists[key] * st.grads[key][col][:, None]
        p = st.world[frame][:, :3, 3]
        out = np.empty_like(S)
        out[:, 3:] = S[:, :3]
        w, v = S[:, :3], S[:, 3:]
        out[:, 0] = v[:, 0] + w[:, 1] * p[:, 2, None] - w[:, 2] * p[:, 1, None]     # v0 + omega x p
        out[:, 1] = v[:, 1] + w[:, 2] * p[:, 0, None] - w[:, 0] * p[:, 2, None]
        out[:, 2] = v[:, 2] + w[:, 0] * p[:, 1, None] - w[:, 1] * p[:, 0, None]
        return out

    # ------------------------------------------------------------------ loop equations
    def loop_rows(self, lp) -> list[int]:
        """Residual components a loop constrains.

        Parameters
        ----------
        lp : evotol.robots.mechanism.description.parts.Loop
            The loop.

        Returns
        -------
        list of int
            Indices into ``[p_b - p_a (0-2); rotation vector (3-5)]``: all six, or 0-2 for a
            ``"position"`` loop; in a planar mechanism only those of 0, 1, 5 (x, y, rotation about z).
        """
        comps = [0, 1, 2, 3, 4, 5] if lp.components == "all" else [0, 1, 2]
        return [c for c in comps if c in IN_PLANE] if self.mech.planar else comps

    def loop_residual(self, st: State) -> np.ndarray:
        """Closure error of every loop (n, m): [p_b - p_a; rotation vector of R_b R_a^T] (m, rad).

        Parameters
        ----------
        st : State
            Kinematic state (world transforms).

        Returns
        -------
        (n, m) ndarray
            The constrained components (:meth:`loop_rows`) of every loop, stacked in loop order;
            (n, 0) without loops.
        """
        out = []
        for lp in self.mech.loops:
            Ta, Tb = st.world[lp.a], st.world[lp.b]
            r = np.concatenate([Tb[:, :3, 3] - Ta[:, :3, 3],
                                rotation_vector(Tb[:, :3, :3] @ np.swapaxes(Ta[:, :3, :3], 1, 2))], axis=1)
            out.append(r[:, self.loop_rows(lp)])
        return np.concatenate(out, axis=1) if out else np.zeros((st.n, 0))

    def loop_jacobian(self, st: State, columns) -> np.ndarray:
        """Derivative of :meth:`loop_residual` per unit change of each column (first order).

        Parameters
        ----------
        st : State
            State with twists and the derivatives with respect to the name columns.
        columns : sequence of str or (str, str)
            As in :meth:`frame_jacobian`.

        Returns
        -------
        (n, m, len(columns)) ndarray
            Motion of frame ``b`` minus that of frame ``a`` for each loop, the constrained rows
            (m or rad per m or rad).
        """
        out = []
        for lp in self.mech.loops:
            J = self.frame_jacobian(st, lp.b, columns) - self.frame_jacobian(st, lp.a, columns)
            out.append(J[:, self.loop_rows(lp)])
        return np.concatenate(out, axis=1) if out else np.zeros((st.n, 0, len(columns)))

    def loop_row_is_length(self) -> np.ndarray:
        """Which rows of :meth:`loop_residual` are lengths (m) rather than angles (rad).

        Returns
        -------
        (m,) ndarray of bool
            True for a position row; used to scale the residual by the mechanism's length.
        """
        return np.array([r < 3 for lp in self.mech.loops for r in self.loop_rows(lp)], bool)
