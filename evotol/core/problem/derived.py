"""Derived tolerance problems: copies of a :class:`~evotol.core.problem.ToleranceProblem` with another
requirement, other or more poses, or changed interval fields (``with_*``, ``at_poses``). Each copy
reuses what it can of the original's cached sensitivities and support coefficients, and starts
with empty measure caches (``ToleranceProblem.__copy__``).
"""
from __future__ import annotations

import copy
import dataclasses
from typing import Self

import numpy as np

from evotol.core import plausibility
from evotol.measures import linear as measures
from evotol.errors import ValidationError
from evotol._runtime.keyword_checks import did_you_mean

__all__ = ["DerivedProblems"]


class DerivedProblems:
    """The ``with_*`` / ``at_poses`` copies of a :class:`~evotol.core.problem.ToleranceProblem` (a mixin
    of that class: it reads the problem's requirement, poses, Jacobian, tolerances and caches).
    """

    def with_requirement(self, **changes) -> Self:
        """A copy with some requirement fields changed (shares the cached sensitivities).

        Parameters
        ----------
        **changes
            :class:`Requirement` fields and their new values (``position`` in m, ``orientation``
            in rad, ``measure`` ...), as for :func:`dataclasses.replace`.

        Returns
        -------
        ToleranceProblem
            The copy; measure caches start empty.

        Raises
        ------
        evotol.errors.ValidationError
            The changed requirement is invalid, or its measure cannot judge the problem's
            clearance sources.
        TypeError
            A name that is not a :class:`Requirement` field.
        """
        new = copy.copy(self)
        new.requirement = dataclasses.replace(self.requirement, **changes)
        new.requirement.validate()
        if self.clearances is not None:
            self._check_clearance_measure(new.requirement)
        new.warnings = plausibility.problem_warnings(new)      # they read the requirement (not issued again)
        return new

    def with_poses(self, idx) -> Self:
        """A copy on the subset ``idx`` of the poses (indices or boolean mask), reusing the
        sensitivities already computed (no call to the robot).

        Parameters
        ----------
        idx : array_like of int, or bool ndarray, shape (n_poses,)
            Pose indices (negative ones count from the end) or a boolean mask over the poses.

        Returns
        -------
        ToleranceProblem
            The copy on the selected poses.

        Raises
        ------
        evotol.errors.ValidationError
            A mask of the wrong shape, an empty selection, or indices that are not integers in
            ``[-n_poses, n_poses)``.
        """
        idx = np.asarray(idx)
        if idx.dtype == bool:
            if idx.shape != (self.n_poses,):
                raise ValidationError("idx", idx.shape, f"a boolean mask of shape ({self.n_poses},)")
            idx = np.flatnonzero(idx)
        if idx.size == 0:
            raise ValidationError("poses", [], "at least one workspace pose")
        if not np.issubdtype(idx.dtype, np.integer) or idx.min() < -self.n_poses or idx.max() >= self.n_poses:
            raise ValidationError("idx", idx.tolist()[:5], f"pose indices in [0, {self.n_poses})")
        new = copy.copy(self)
        new.poses = self.poses[idx]
        new._set_jacobian(self.jacobian[idx])
        new._coeff_cache = {k: (v[0][idx],) + tuple(v[1:3]) + ((v[3][idx],) if len(v) > 3 else ())
                            for k, v in self._coeff_cache.items()}
        return new

    def at_poses(self, poses) -> Self:
        """A copy on other poses (same tolerances and requirement; sensitivities computed for them).

        Parameters
        ----------
        poses : array_like, shape (n, workspace.dim)
            The new workspace poses (SI: m, rad), at least one.

        Returns
        -------
        ToleranceProblem
            The copy on ``poses``.

        Raises
        ------
        evotol.errors.ValidationError
            No pose, a malformed pose array, or sensitivities that are not finite there.
        evotol.errors.KinematicsError
            A pose outside the robot's workspace.
        """
        P = self._check_pose_set(poses)
        J = np.asarray(self.error_model.sensitivity(P), dtype=float)
        if J.shape != (len(P), 6, self.error_model.n_columns) or not np.all(np.isfinite(J)):
            raise ValidationError(f"{self.error_model.name}.sensitivity", P.tolist()[:3], "finite sensitivities at the poses")
        new = copy.copy(self)
        new.poses = P
        new._set_jacobian(J)
        new._coeff_cache = {}
        return new

    def with_tolerances(self, **fields) -> Self:
        """A copy with some :class:`Tolerance` fields changed for every source (a scalar, or an
        array/sequence in source order), e.g. ``with_tolerances(offset=c)`` to evaluate interval
        designs [c − t, c + t]; reuses the sensitivities, re-validates every tolerance.

        Parameters
        ----------
        **fields
            Any of ``offset`` (SI: m or rad), ``minus``, ``plus`` (dimensionless factors),
            ``cost_width`` and ``contains_nominal``; each a scalar for every source or one value
            per source, shape (n_sources,).

        Returns
        -------
        ToleranceProblem
            The copy with the changed tolerances.

        Raises
        ------
        evotol.errors.ValidationError
            A field not in the list above, a value of the wrong shape, or a tolerance made invalid.
        """
        allowed = ("offset", "minus", "plus", "cost_width", "contains_nominal")
        for k in fields:
            if k not in allowed:
                raise ValidationError(f"with_tolerances.{k}", k, f"one of {allowed}" + did_you_mean(k, allowed))
        n = self.n_sources
        tols = {}
        for j, nm in enumerate(self.names):
            ch = {}
            for k, v in fields.items():
                arr = np.asarray(v, dtype=object if isinstance(v, str) else float)
                ch[k] = (arr.item() if arr.ndim == 0 else (float(arr[j]) if arr.shape == (n,) else None))
                if ch[k] is None:
                    raise ValidationError(k, np.shape(v), f"a scalar or one value per source ({n})")
            tols[nm] = dataclasses.replace(self.tolerances[nm], **ch)
        for nm, src in zip(self.names, self.error_model.sources):
            tols[nm].validate(nm, src.dim)
        new = copy.copy(self)
        new.tolerances = tols
        new.shape = measures.IntervalShape(np.array([t.rho for t in tols.values()]),
                                           np.array([t.kappa for t in tols.values()]),
                                           np.array([float(t.offset) for t in tols.values()]))
        same = all(np.array_equal(getattr(new.shape, f), getattr(self.shape, f)) for f in ("rho", "kappa", "offset"))
        # the support coefficients depend on the poses' blocks and the intervals' shape only: a drawing's
        # re-check of centred zones keeps them (0.75 s at 1 000 poses), a new shape computes its own
        new._coeff_cache = dict(self._coeff_cache) if same else {}
        return new

    def with_added_poses(self, poses) -> Self:
        """A copy with more poses appended (sensitivities computed only for the new ones).

        Parameters
        ----------
        poses : array_like, shape (n, workspace.dim)
            Poses to append (SI: m, rad).

        Returns
        -------
        ToleranceProblem
            The copy on the old poses followed by ``poses``.

        Raises
        ------
        evotol.errors.ValidationError
            A malformed pose array, or sensitivities that are not finite at the new poses.
        evotol.errors.KinematicsError
            A pose outside the robot's workspace.
        """
        P = self.error_model.check_poses(poses)
        J = np.asarray(self.error_model.sensitivity(P), dtype=float)
        if not np.all(np.isfinite(J)):
            raise ValidationError(f"{self.error_model.name}.sensitivity", P.tolist()[:3], "finite sensitivities at the added poses")
        new = copy.copy(self)
        new.poses = np.vstack([self.poses, P])
        new._set_jacobian(np.concatenate([self.jacobian, J], axis=0))
        new._coeff_cache = {}
        return new
