"""Per-pose linear maps of one decoupled block of a clearance mechanism: the target rows ``C`` and
the loop-equation map ``B`` (Deng 2012 eqs. III.22-III.24, V.1-V.4; ``B^T s = 0`` for consistent
screws ``s``), computed once by :meth:`evotol.robots.clearance.model.ClearanceMechanism.pose_maps` and
reused for any clearance bounds."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from evotol.robots.clearance.parts import Block


@dataclass
class PoseMaps:
    """Per-pose linear maps of one decoupled block, computed once and reused for any bounds.

    cols: (n_rows,) index into the stacked screw vector (6 * n_joints) of each row, in cone order;
    cone_joint, cone_kind: joint index and bound kind (0..3) of each cone; disks come first
    (``n_disk`` cones of 2 rows), then intervals (1 row each).
    C_pos, C_rot: (n_poses, k, n_rows) -- target twist components (base frame) of a consistent
    screw vector; B: (n_poses, n_rows, m) -- consistency ``B^T s = 0``.

    Parameters
    ----------
    block : Block
        The decoupled block of components these maps belong to.
    cols : (n_rows,) int ndarray
        Index of each row in the stacked screw vector (``6 * n_joints``), in cone order.
    cone_joint : (n_cones,) int ndarray
        Joint index of each cone.
    cone_kind : (n_cones,) int ndarray
        Bound kind of each cone (0-3: ``beta_xy, beta_z, b_xy, b_z``).
    n_disk : int
        Number of disk cones (2 rows each), which come first.
    pos_comps : tuple of int
        Twist components (3-5) of the position rows of ``C_pos``.
    rot_comps : tuple of int
        Twist components (0-2) of the rotation rows of ``C_rot``.
    C_pos : (n_poses, k_pos, n_rows) ndarray
        End-effector position error (m, base axes) per unit screw row (rad or m).
    C_rot : (n_poses, k_rot, n_rows) ndarray
        End-effector rotation error (rad, base axes) per unit screw row.
    B : (n_poses, n_rows, m) ndarray
        Loop-equation map: consistent screws satisfy ``B^T s = 0`` (``m`` loop columns).
    groups : tuple, optional
        Sparsity of ``B``: tuples ``(disk cone indices, interval row indices, loop columns)``;
        the rows of a group are zero outside its columns. Empty (default): dense.
    """

    block: Block
    cols: np.ndarray
    cone_joint: np.ndarray
    cone_kind: np.ndarray
    n_disk: int
    pos_comps: tuple[int, ...]
    rot_comps: tuple[int, ...]
    C_pos: np.ndarray
    C_rot: np.ndarray
    B: np.ndarray
    #: sparsity of B: tuples (disk cone indices, interval row indices, loop columns) -- the rows of
    #: a group are zero outside its columns (each loop touches few chains)
    groups: tuple = ()

    @property
    def n_rows(self) -> int:
        """int: number of screw rows (scalar screw components) in the block."""
        return len(self.cols)

    @property
    def n_loops(self) -> int:
        """int: number of loop-equation columns ``m`` of ``B``."""
        return self.B.shape[-1]

    def row_bounds(self, bounds: np.ndarray) -> np.ndarray:
        """Bound of every row, (..., n_rows), from a bounds array (..., n_joints, 4).

        Parameters
        ----------
        bounds : (..., n_joints, 4) ndarray
            Columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.

        Returns
        -------
        (..., n_rows) ndarray
            The bound (rad or m) of each row's cone; a disk's bound repeated on its two rows.
        """
        per_cone = bounds[..., self.cone_joint, self.cone_kind]
        nd = self.n_disk
        return np.concatenate([np.repeat(per_cone[..., :nd], 2, axis=-1), per_cone[..., nd:]], axis=-1)

    def take(self, idx) -> "PoseMaps":
        """The maps at some poses.

        Parameters
        ----------
        idx : int array or slice
            Pose indices (or a boolean mask).

        Returns
        -------
        PoseMaps
            A copy with ``C_pos``, ``C_rot`` and ``B`` indexed by ``idx`` along the pose axis.
        """
        return replace(self, C_pos=self.C_pos[idx], C_rot=self.C_rot[idx], B=self.B[idx])

    def sample_screws(self, i: int, bounds: np.ndarray, n: int, rng, mode: str = "uniform") -> np.ndarray:
        """``n`` random consistent clearance states at pose ``i``: the rows of the screw vector,
        (n, n_rows), m and rad. Each joint's screw is drawn in its clearance set (``"uniform"``:
        uniformly inside the disks and intervals; ``"boundary"``: on their boundaries), the part
        violating the loop equations is removed (orthogonal projection onto ``B^T s = 0``, rows
        scaled by their bounds) and the sample is scaled back into the set. ``bounds``: (n_joints, 4).

        Parameters
        ----------
        i : int
            Pose index.
        bounds : (n_joints, 4) ndarray
            Columns ``[beta_xy (rad), beta_z (rad), b_xy (m), b_z (m)]``.
        n : int
            Number of samples.
        rng : numpy.random.Generator
            Random number generator.
        mode : str, optional
            ``"boundary"``: on the boundaries of the disks and intervals; ``"uniform"`` (default,
            and any other value): uniformly inside.

        Returns
        -------
        (n, n_rows) ndarray
            Consistent screw rows (rad, m) inside the clearance set, in the order of ``cols``.
        """
        D = self.row_bounds(bounds[None])[0]
        nd = self.n_disk
        ni = self.n_rows - 2 * nd
        ang = rng.uniform(0, 2 * np.pi, (n, nd))
        sig = np.empty((n, 2 * nd + ni))       # disks' pairs, then intervals, written in place
        np.cos(ang, out=sig[:, 0:2 * nd:2])
        np.sin(ang, out=sig[:, 1:2 * nd:2])
        if mode == "boundary":                 # on the circles: radius 1 (the same numbers as 1 * cos)
            sig[:, 2 * nd:] = rng.choice([-1.0, 1.0], (n, ni))
        else:
            sig[:, :2 * nd] *= np.repeat(np.sqrt(rng.uniform(0, 1, (n, nd))), 2, axis=1)
            sig[:, 2 * nd:] = rng.uniform(-1, 1, (n, ni))
        Bt = self.B[i] * D[:, None]
        if Bt.shape[1]:
            sig = sig - (sig @ Bt) @ np.linalg.pinv(Bt)      # orthogonal projection onto B^T s = 0
        x, y = sig[:, 0:2 * nd:2], sig[:, 1:2 * nd:2]
        nrm_d = np.sqrt(x * x + y * y).max(-1, initial=0.0)
        nrm_i = np.abs(sig[:, 2 * nd:]).max(-1, initial=0.0)
        return sig / np.maximum(np.maximum(nrm_d, nrm_i), 1.0)[:, None] * D
