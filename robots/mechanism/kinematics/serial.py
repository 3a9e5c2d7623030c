"""The fast path of a serial chain (a URDF arm, or any description without loops): the frames from
the base to the end-effector folded into stages, and the sources into terms, for the compiled
kernels of :mod:`evotol.robots.mechanism.kinematics.serial_kernels` and
:mod:`evotol.robots.mechanism.kinematics.serial_newton`.

Why: the general description machinery evaluates every DH entry as an expression and builds every
frame's twists with NumPy over all poses; for a 6-joint arm that is about 35 frames of small array
operations per call, 7-80x slower than Pinocchio's C++ regressor loop (issue 23). A serial chain
needs none of it: each stage is a constant 4x4 and one joint value ``a q + c``, and one compiled
loop over poses does forward kinematics, sensitivities, perturbed forward kinematics (Monte Carlo)
and the continued Newton inverse geometry, with the same equations as
:class:`evotol.robots.mechanism.kinematics.tree.Kinematics` (``tests/test_serial_fast_path.py`` compares them).

A chain qualifies when the mechanism has no loops and no points, is not planar, its end-effector
is a frame, and on the path every DH entry is a constant except the joint field of a joint row,
which is affine in one joint variable (``J``, ``"q1 - pi"``, a mimic joint's ``"m * L + o"``).
Sources qualify when they are placement errors (``F.tilt_x`` ...), joint offsets (actuated
variables), a joint row's joint entry (``F.theta``) or parameters used only in joint entries (a
mimic joint's offset and multiplier). Otherwise :meth:`SerialChain.build` returns None and the
general path serves.
"""
from __future__ import annotations

import logging
import threading

import numpy as np

from evotol.robots.clearance.newton_kernel import AVAILABLE as SERIAL_COMPILED   # numba importable, EVOTOL_NO_NUMBA unset
from evotol.robots.mechanism.kinematics.placement import PLACEMENT_FIELDS

logger = logging.getLogger(__name__)


_ANNOUNCED = []


def _kernels():
    """The compiled kernels; one log line (INFO, standard error under the ``evotol`` command) the first
    time a process finds no compiled copy in numba's on-disk cache (a fresh install compiles them once,
    up to about 40 s on a 2-core machine), so it does not look hung."""
    import os

    from evotol.robots.mechanism.kinematics import serial_kernels

    if not _ANNOUNCED:
        _ANNOUNCED.append(True)
        try:
            index = serial_kernels.sensitivity._cache._cache_file._index_path   # numba internals; silent if they change
        except AttributeError:
            return serial_kernels
        if not os.path.exists(index):
            logger.info("compiling the serial-arm kernels with numba (once per install, up to about 40 s; cached in %s)",
                        os.path.dirname(index))
    return serial_kernels


def _kk(g, b, al, d) -> np.ndarray:
    """Rot(z,g) Trans(z,b) Rot(x,al) Trans(x,d) (4x4)."""
    cg, sg, ca, sa = np.cos(g), np.sin(g), np.cos(al), np.sin(al)
    return np.array([[cg, -sg * ca, sg * sa, d * cg], [sg, cg * ca, -cg * sa, d * sg], [0.0, sa, ca, b], [0, 0, 0, 1.0]])


def _motion(th, r) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1.0, r], [0, 0, 0, 1.0]])


class SerialChain:
    """Stages and terms of a serial description (see the module docstring); build with :meth:`build`."""

    def __init__(self):
        self.P, self.kind, self.var, self.a, self.c, self.mark = [], [], [], [], [], []
        self.mark_of = {}               # frame -> mark index (its placement)
        self.stage_of = {}              # joint frame -> stage index
        self._mc = None                 # the Monte Carlo kernel's program (serial_montecarlo.program), on first use
        self._sens = None               # the sensitivity kernel's terms (column, mark, field, coefficient, variable)

    # ------------------------------------------------------------------ construction
    @classmethod
    def build(cls, kin, columns) -> "SerialChain | None":
        """The fast path for ``kin`` (a :class:`Kinematics`) and source ``columns``, or None.

        Parameters
        ----------
        kin : evotol.robots.mechanism.kinematics.tree.Kinematics
            Kinematics of the description.
        columns : sequence of str or (str, str)
            The model's source columns: a parameter or actuated joint variable name, or a DH
            entry / placement error ``(frame, field)``
            (:class:`~evotol.robots.mechanism.model.error_model.MechanismModel` ``.columns``).

        Returns
        -------
        SerialChain or None
            The stages and terms, or None when the chain or a source does not qualify (see the
            module docstring): the general path serves then.
        """
        mech = kin.mech
        if mech.loops or mech.points or mech.planar or mech.end_effector not in kin.tree.frames:
            return None
        params = mech.parameters
        ch = cls()
        ch.variables = list(kin.variables)
        need = {c[0] for c in columns if isinstance(c, tuple)}
        pending = np.eye(4)
        path = kin.tree.path(mech.end_effector)
        for i, fname in enumerate(path):
            f = kin.tree.frames[fname]
            vals = {}
            jf = {0: "theta", 1: "r"}.get(f.sigma)
            for k in ("gamma", "b", "alpha", "d", "theta", "r"):
                e = kin.expr[(fname, k)]
                if k == jf:
                    continue
                if e.names - set(params):
                    return None
                vals[k] = float(np.real(e(params)))
            if jf is None:                                         # fixed row: placement = the frame itself
                T = _kk(vals["gamma"], vals["b"], vals["alpha"], vals["d"]) @ _motion(vals["theta"], vals["r"])
                pending = pending @ T
                if fname in need or i == len(path) - 1:
                    ch._stage(pending, 0, 0, 0.0, 0.0, fname)
                    pending = np.eye(4)
                continue
            e = kin.expr[(fname, jf)]
            vs = [x for x in e.names if x in kin.variables]
            if len(vs) != 1:
                return None
            v = vs[0]
            lin = ch._affine(e, v, params)
            if lin is None:
                return None
            pre = pending @ _kk(vals["gamma"], vals["b"], vals["alpha"], vals["d"])
            ch.stage_of[fname] = len(ch.P)
            ch._stage(pre, 1 if jf == "theta" else 2, kin.variables.index(v), lin[0], lin[1], fname)
            # a constant r of a revolute row (theta of a prismatic one) commutes with the motion: next stage
            pending = _motion(0.0, vals["r"]) if jf == "theta" else _motion(vals["theta"], 0.0)
        if not np.allclose(pending, np.eye(4)):
            ch._stage(pending, 0, 0, 0.0, 0.0, None)
        ch.kin, ch.params = kin, params
        if not ch._terms(columns):
            return None
        ch.P = np.ascontiguousarray(ch.P, float)
        ch.ident = np.array([np.array_equal(P, np.eye(4)) for P in ch.P], np.bool_)
        for k in ("kind", "var", "mark"):
            setattr(ch, k, np.asarray(getattr(ch, k), np.int64))
        ch.a, ch.c = np.asarray(ch.a, float), np.asarray(ch.c, float)
        ch.n_marks = len(ch.mark_of)
        return ch

    def _stage(self, P, kind, var, a, c, frame):
        self.P.append(P)
        self.kind.append(kind)
        self.var.append(var)
        self.a.append(a)
        self.c.append(c)
        if frame is None:
            self.mark.append(-1)
        else:
            self.mark_of[frame] = len(self.mark_of)
            self.mark.append(self.mark_of[frame])

    @staticmethod
    def _affine(e, v, params):
        """(a, c) with e = a v + c for the parameters' values, or None when e is not affine in v."""
        x = np.array([0.0, 1.0, 2.5])
        y = np.real(e({**params, v: x})) * np.ones(3)
        a, c = y[1] - y[0], y[0]
        return (float(a), float(c)) if np.allclose(y, a * x + c, rtol=1e-12, atol=1e-12) else None

    def _terms(self, columns) -> bool:
        """Placement terms (column, mark, field) and joint terms (column, stage, coef, var)."""
        kin, params = self.kin, self.params
        pl, jt, vt = [], [], []
        for col, c in enumerate(columns):
            if isinstance(c, tuple) and c[1] in PLACEMENT_FIELDS:
                if c[0] in self.mark_of:
                    pl.append((col, self.mark_of[c[0]], PLACEMENT_FIELDS.index(c[1])))
                elif c[0] in kin.paths[kin.mech.end_effector]:
                    return False                                   # folded away: cannot happen for needed frames
                continue
            if isinstance(c, tuple):                               # a DH entry: only a joint row's joint entry
                fr, k = c
                if fr not in self.stage_of or k != {1: "theta", 2: "r"}[self.kind[self.stage_of[fr]]]:
                    if fr in kin.paths[kin.mech.end_effector]:
                        return False
                    continue
                jt.append((col, self.stage_of[fr], 1.0, -1))
                continue
            for fr, s in self.stage_of.items():                    # a joint variable or a parameter
                k = {1: "theta", 2: "r"}[self.kind[s]]
                e = kin.expr[(fr, k)]
                if c not in e.names:
                    continue
                if c in kin.variables:
                    continue
                v = self.variables[self.var[s]]
                y = [np.real(e({**params, c: params[c] + h, v: 1.0})) for h in (0.0, 0.5, 1.0)]
                if not np.isclose(y[2] - y[0], 2 * (y[1] - y[0]), rtol=1e-12, atol=1e-12):
                    return False                                   # not affine in the parameter: not exact here
                d = []
                for x in (0.0, 1.0, 2.5):
                    _, g = e.value_and_gradient({**params, v: np.array(x)}, {c})
                    d.append(float(g[c]))
                slope = d[1] - d[0]
                if not np.isclose(d[2], d[0] + 2.5 * slope, rtol=1e-12, atol=1e-12):
                    return False
                if d[0]:
                    jt.append((col, s, d[0], -1))
                if slope:
                    jt.append((col, s, slope, self.var[s]))
            if c in kin.variables:
                vt.append((col, self.variables.index(c)))
            if c not in kin.variables and any(c in kin.expr[(f, k)].names for f in kin.paths[kin.mech.end_effector]
                                              for k in ("gamma", "b", "alpha", "d", "theta", "r")
                                              if f not in self.stage_of or k not in ("theta", "r")):
                return False                                       # a parameter of a constant entry
        self.p_terms = np.array(pl, np.int64).reshape(-1, 3)
        self.j_col = np.array([t[0] for t in jt], np.int64)
        self.j_stage = np.array([t[1] for t in jt], np.int64)
        self.j_coef = np.array([t[2] for t in jt], float)
        self.j_var = np.array([t[3] for t in jt], np.int64)
        self.v_col = np.array([t[0] for t in vt], np.int64)          # joint offsets: q[var] += e[col]
        self.v_var = np.array([t[1] for t in vt], np.int64)
        self.n_cols = len(columns)
        return True

    # ------------------------------------------------------------------ evaluation
    def _args(self):
        return self.P, self.ident, self.kind, self.var, self.a, self.c, self.mark, self.n_marks

    def _joint_stages(self):
        """The joint stages' indices, variables and coefficients ``a`` (the Newton and posture kernels' joint
        columns), contiguous arrays."""
        js = np.flatnonzero(self.kind > 0).astype(np.int64)
        return js, self.var[js].copy(), self.a[js].copy()

    def joints_array(self, q: dict) -> np.ndarray:
        """Joint values as the kernels take them.

        Parameters
        ----------
        q : dict of str to (n,) array_like
            Every joint variable of the chain -> its values (rad or m).

        Returns
        -------
        (n, n_vars) ndarray
            C-contiguous, columns in the order of ``variables``.

        Raises
        ------
        KeyError
            A joint variable missing from ``q``.
        """
        return np.ascontiguousarray(np.stack([np.asarray(q[v], float) for v in self.variables], axis=1))

    def sensitivity(self, Q: np.ndarray) -> np.ndarray:
        """(n, 6, n_cols) at joint values Q (n, n_vars).

        Parameters
        ----------
        Q : (n, n_vars) ndarray
            Joint values (rad or m), columns in the order of ``variables``.

        Returns
        -------
        (n, 6, n_cols) ndarray
            ``[dp (m); dphi (rad)]`` of the tip in the base frame per unit of each source column
            (m or rad), as :meth:`MechanismModel.sensitivity
            <evotol.robots.mechanism.model.error_model.MechanismModel.sensitivity>`.
        """
        K = _kernels()
        if self._sens is None:                     # the terms of the kernel, built once (a call of 1 000 poses is ~0.5 ms)
            vs = [(c, s) for c, v in zip(self.v_col, self.v_var) for s in np.flatnonzero((self.var == v) & (self.kind > 0))]
            j_col = np.concatenate([self.j_col, np.array([c for c, _ in vs], np.int64)])
            j_stage = np.concatenate([self.j_stage, np.array([s for _, s in vs], np.int64)])
            j_coef = np.concatenate([self.j_coef, self.a[[s for _, s in vs]]])
            j_var = np.concatenate([self.j_var, np.full(len(vs), -1, np.int64)])
            self._sens = (np.concatenate([self.p_terms[:, 0], j_col]), np.concatenate([self.p_terms[:, 1], self.mark[j_stage]]),
                          np.concatenate([self.p_terms[:, 2], np.where(self.kind[j_stage] == 1, 5, 2)]),
                          np.concatenate([np.ones(len(self.p_terms)), j_coef]),
                          np.concatenate([np.full(len(self.p_terms), -1, np.int64), j_var]))
        return K.sensitivity(*self._args(), np.ascontiguousarray(Q, float), *self._sens, self.n_cols)

    def pose_error(self, Q: np.ndarray, errors: np.ndarray) -> np.ndarray:
        """(n, m, 6) nonlinear tip error for errors (n, m, n_cols) at joint values Q (n, n_vars), by the
        batched kernel of :mod:`evotol.robots.mechanism.kinematics.serial_montecarlo`.

        Parameters
        ----------
        Q : (n, n_vars) ndarray
            Nominal joint values (rad or m), columns in the order of ``variables``.
        errors : (n, m, n_cols) array_like
            Source errors (m or rad), ``m`` samples per configuration.

        Returns
        -------
        (n, m, 6) ndarray
            ``[dp (m); rotation vector (rad)]`` of the perturbed tip relative to the nominal, base
            frame.
        """
        from evotol.robots.mechanism.kinematics import serial_montecarlo as mc

        _kernels()
        if self._mc is None:
            self._mc = mc.program(self)
        errors = np.asarray(errors, float)                     # broadcast views as they are
        args = (self.P, self.kind, self.var, self.a, self.c, *self._mc, self.v_col, self.v_var, np.ascontiguousarray(Q, float))
        # from any thread: the kernels run on threads of their own from the main thread, in the caller's otherwise
        if errors.shape[0] > 1 and errors.strides[0] == 0 and not (self.j_var >= 0).any():
            return mc.pose_error_shared(*args, errors[0])      # the same samples at every pose (verify_nonlinear)
        return mc.pose_error(*args, errors)

    def _pose_error_scalar(self, Q: np.ndarray, errors: np.ndarray) -> np.ndarray:
        """:meth:`pose_error` by the scalar kernel it replaced (issue 43: one sample at a time, the whole
        chain and ``sin``/``cos`` per sample), kept for ``benchmarks/bench_urdf.py``'s before/after."""
        K = _kernels()
        kernel = K.pose_error if threading.current_thread() is threading.main_thread() else K.pose_error_serial
        p = self.p_terms
        return kernel(*self._args(), np.ascontiguousarray(Q, float), np.asarray(errors, float),
                      p[:, 0].copy(), p[:, 1].copy(), p[:, 2].copy(), self.j_col, self.j_stage, self.j_coef, self.j_var,
                      self.v_col, self.v_var)

    def inverse_geometry(self, q0: np.ndarray, targets: np.ndarray, Rts: np.ndarray | None, axes, scale: float):
        """(Q (n, n_vars), scaled residual (n,), evaluations (n,)) continued from q0 through targets
        (K, n, n_axes).

        One Gauss-Newton correction per intermediate step, up to 40 iterations (tolerance 1e-12,
        or the damped steps' floor: :data:`~evotol.robots.mechanism.kinematics.serial_kernels.FLOOR`)
        at the last; a redundant arm keeps the posture nearest ``q0``.

        Parameters
        ----------
        q0 : (n_vars,) array_like
            Assembly joint values (rad or m), the starting point of every pose.
        targets : (K, n, n_axes) ndarray
            Target tip coordinates (m) of the ``K`` continuation steps, the last the poses.
        Rts : (K, n, 3, 3) ndarray or None
            Target orientations of the tip per step (a broadcast view with zero strides where one
            orientation holds at every step or pose), or None when the orientation is free.
        axes : sequence of int
            Base axis (0 x, 1 y, 2 z) of each target coordinate.
        scale : float
            Length (m) dividing the position residuals (the mechanism's largest length).

        Returns
        -------
        Q : (n, n_vars) ndarray
            Joint values at the poses (rad or m).
        residual : (n,) ndarray
            Largest scaled residual per pose (dimensionless); the caller checks it.
        evaluations : (n,) ndarray of int
            Forward kinematics and Jacobian evaluations per pose (continuation steps included).
        """
        from evotol.robots.mechanism.kinematics import serial_newton

        _kernels()
        has_rot = Rts is not None
        if Rts is None:
            Rts = np.broadcast_to(np.zeros((1, 1, 3, 3)), targets.shape[:2] + (3, 3))
        Rts = np.asarray(Rts, float)                   # zero strides kept: numba indexes views as they are
        return serial_newton.inverse_geometry(*self._args(), np.asarray(q0, float), np.ascontiguousarray(targets, float),
                                  Rts, has_rot, np.asarray(axes, np.int64), *self._joint_stages(), float(scale), 40,
                                  1e-12)


def serial_inverse_geometry(kin, chain: SerialChain, poses: np.ndarray, max_step: float = 0.1) -> dict:
    """:meth:`Kinematics.inverse_geometry` for a serial chain, compiled: the same continuation from
    the assembly configuration (straight paths, steps of at most ``max_step`` of the box, one
    Gauss-Newton correction per intermediate step, full convergence at the pose, the posture
    nearest the assembly for a redundant arm), the same errors (out of reach, joint limits).

    Shares the cache of ``kin`` (the returned dict is shared, do not modify it).

    Parameters
    ----------
    kin : evotol.robots.mechanism.kinematics.tree.Kinematics
        Kinematics of the description (its assembly, coordinates and orientation targets).
    chain : SerialChain
        The fast path built from ``kin``.

    Returns
    -------
    dict of str to (n,) ndarray
        Every joint variable at the poses (rad or m).

    Raises
    ------
    evotol.errors.KinematicsError
        A pose out of reach or singular (scaled residual not below 1e-9), or a joint outside its
        limits, naming the first such pose; or a failed assembly
        (:meth:`Kinematics.assembly <evotol.robots.mechanism.posture.inverse_geometry.InverseGeometry.assembly>`).
    evotol.errors.ValidationError
        From the assembly (an ``[assembly] joints`` key that is not a joint variable).
    """
    from evotol.errors import KinematicsError
    from evotol.robots.mechanism.description.limits import check_joint_limits, unreachable_message

    poses = np.atleast_2d(np.asarray(poses, float))
    key = poses.tobytes()
    if key in kin._cache:
        return kin._cache[key]
    x0, q0 = kin.assembly()
    mech = kin.mech
    n = len(poses)
    span = np.array([max(c.high - c.low, 1e-12) for c in mech.coordinates])
    dist = np.abs((poses - x0) / span).max() if n else 0.0
    K = int(np.clip(np.ceil(dist / max_step), 1, 200))
    steps = np.linspace(1.0 / K, 1.0, K)
    targets = x0 + steps[:, None, None] * (poses - x0)[None]
    Rts = None
    if kin.orientation and not any(e.names & {c.name for c in mech.coordinates} for _, e in kin.orientation):
        Rts = np.broadcast_to(kin._target_orientation(x0[None]), targets.shape[:2] + (3, 3))   # the same at every target
    elif kin.orientation:
        Rts = kin._target_orientation(targets.reshape(-1, targets.shape[2])).reshape(targets.shape[:2] + (3, 3))
    idx = [i for i, _ in kin.coord_axes]
    axes = [ax for _, ax in kin.coord_axes]
    Q, res, _ = chain.inverse_geometry(np.array([q0[v] for v in chain.variables]), targets[:, :, idx], Rts, axes,
                                    kin.length_scale)
    bad = ~(res < 1e-9)
    if bad.any():
        raise KinematicsError(unreachable_message(mech, poses, bad, res), poses=poses[bad])
    q = {v: Q[:, i].copy() for i, v in enumerate(chain.variables)}
    check_joint_limits(mech.name, mech.limits, q, poses, [c.name for c in mech.coordinates])
    if len(kin._cache) > 8:
        kin._cache.clear()
    kin._cache[key] = q
    return q
