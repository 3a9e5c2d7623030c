"""A linear test robot with fixed random sensitivities (not a plugin: test helper)."""
import numpy as np

from evotol.robots.base import RobotErrorModel, SourceSpec, Workspace


class ToyRobot(RobotErrorModel):
    def __init__(self, dims=(1, 1, 2, 2, 1), n_poses_axis=1, seed=0, planar=False):
        rng = np.random.default_rng(seed)
        self.name = "toy"
        self.sources = tuple(SourceSpec(f"s{j}", d, "m", "length" if d == 1 else "joint") for j, d in enumerate(dims))
        self.workspace = Workspace(("x",), (0.0,), (1.0,), ("m",))
        self._A = rng.normal(size=(6, self.n_columns))
        self._B = rng.normal(size=(6, self.n_columns))
        if planar:
            self._A[2:5] = 0
            self._B[2:5] = 0

    def sensitivity(self, poses):
        x = self.check_poses(poses)[:, 0]
        return self._A[None] + x[:, None, None] * self._B[None]
