"""BranchNetwork: the composite left arm - trunk - right arm PMP network (Sects. 2.5, 3.1, Fig 5).

Two nodes compose the basic PMP networks of the limbs:

- the **sum node** adds the virtual torques that the force fields of the branches (the two
  arms) induce on their common segment (the trunk): ``T_trunk = sum_i T_i,trunk``, where
  ``T_i = J_i^T F_i`` (eq 2) over branch i's chain [trunk joints, arm_i joints];
- the trunk relaxes with its own admittance, ``q_dot_trunk = A_trunk T_trunk`` (eq 3), each arm
  with its own, ``q_dot_arm_i = A_i T_i,arm``;
- the **assignment node** propagates the trunk motion back to every branch, whose end effector
  then moves by ``x_dot_i = J_i [q_dot_trunk; q_dot_arm_i]`` (eq 4).

The two nodes are dual (energy conservation, Sect. 3.1): the assignment node is the transpose
of the sum node. Consequently one relaxation cycle of the whole network equals the basic PMP
of the stacked chain, ``q_dot = A G^T F`` with ``A = blockdiag(A_trunk, A_1, A_2)`` and ``G``
the stacked hand Jacobians over :attr:`joint_names` (zero columns where a hand does not depend
on a joint). The relaxation uses that stacked form (one matrix product per step); the
node-wise methods here define and document the network and are checked against it in the
tests. ``A_trunk`` modulates trunk recruitment: zero grounds both shoulders (stiff trunk), a
larger value lets the trunk extend the reach (compliant trunk, Fig 7).
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from icub_pmp.errors import InvalidInput

__all__ = ["BranchNetwork"]


def _admittance(name: str, values, n: int) -> np.ndarray:
    a = np.array(values, dtype=float).reshape(-1)
    if a.shape != (n,):
        raise InvalidInput(f"{name}: expected {n} admittances, got {a.shape[0]}")
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise InvalidInput(f"{name}: admittances must be finite and >= 0, got {a.tolist()}")
    return a


class BranchNetwork:
    """Trunk joints shared by branches (one per end effector), each with its own joints.

    Args:
        trunk_joints: the common segment's joints (may be empty: grounded shoulders).
        branches: end effector name -> its own joints (e.g. ``{"left": l_arm, "right": r_arm}``).
        trunk_admittance: A_trunk diagonal (len(trunk_joints),) [rad/(s N m)].
        branch_admittance: end effector -> A_i diagonal [rad/(s N m)].
    """

    def __init__(
        self,
        trunk_joints: Sequence[str],
        branches: Mapping[str, Sequence[str]],
        trunk_admittance,
        branch_admittance: Mapping[str, object],
    ):
        if not branches:
            raise InvalidInput("branch network: at least one branch (end effector) is needed")
        self.trunk_joints = tuple(trunk_joints)
        self.branches = {k: tuple(v) for k, v in branches.items()}
        names = list(self.trunk_joints)
        for joints in self.branches.values():
            names.extend(joints)
        if len(set(names)) != len(names):
            raise InvalidInput(f"branch network: a joint appears twice in {names}")
        #: all joints of the network: trunk first, then each branch in order
        self.joint_names: tuple[str, ...] = tuple(names)
        self._index = {n: i for i, n in enumerate(names)}
        nt = len(self.trunk_joints)
        self.trunk_admittance = _admittance("trunk admittance", trunk_admittance, nt)
        self.branch_admittance = {}
        for b, joints in self.branches.items():
            if b not in branch_admittance:
                raise InvalidInput(f"branch network: no admittance given for branch {b!r}")
            self.branch_admittance[b] = _admittance(
                f"{b} admittance", branch_admittance[b], len(joints)
            )
        #: A = blockdiag(A_trunk, A_1, ...) as a diagonal (n,)
        self.admittance = np.concatenate(
            [self.trunk_admittance] + [self.branch_admittance[b] for b in self.branches]
        )
        self.admittance.setflags(write=False)
        self.trunk_slice = slice(0, nt)
        self.branch_slices: dict[str, slice] = {}
        start = nt
        for b, joints in self.branches.items():
            self.branch_slices[b] = slice(start, start + len(joints))
            start += len(joints)

    @property
    def n(self) -> int:
        """Number of joints in the network."""
        return len(self.joint_names)

    def chain_indices(self, branch: str) -> np.ndarray:
        """Indices into :attr:`joint_names` of branch's chain [trunk joints, own joints]."""
        s = self.branch_slices[branch]
        return np.r_[np.arange(len(self.trunk_joints)), np.arange(s.start, s.stop)]

    def sum_node(self, branch_torques: Mapping[str, np.ndarray]) -> np.ndarray:
        """T_trunk = sum_i T_i,trunk: trunk torques from each branch's chain torques."""
        total = np.zeros(len(self.trunk_joints))
        for t in branch_torques.values():
            total += np.asarray(t, dtype=float)[: len(self.trunk_joints)]
        return total

    def assignment_node(
        self, trunk_velocity: np.ndarray, branch_velocities: Mapping[str, np.ndarray]
    ) -> dict[str, np.ndarray]:
        """Chain velocities [q_dot_trunk; q_dot_arm_i] of every branch (the trunk's motion
        assigned to all branches)."""
        tv = np.asarray(trunk_velocity, dtype=float)
        return {b: np.concatenate([tv, np.asarray(v, dtype=float)])
                for b, v in branch_velocities.items()}

    def relax(self, branch_torques: Mapping[str, np.ndarray]) -> np.ndarray:
        """One cycle of Fig 5: chain torques T_i (eq 2) -> network joint velocities (n,) (eq 3).

        ``branch_torques[b]`` is over :meth:`chain_indices` (b), i.e. ``J_b^T F_b``.
        """
        nt = len(self.trunk_joints)
        q_dot = np.zeros(self.n)
        q_dot[self.trunk_slice] = self.trunk_admittance * self.sum_node(branch_torques)
        for b, t in branch_torques.items():
            q_dot[self.branch_slices[b]] = self.branch_admittance[b] * np.asarray(t)[nt:]
        return q_dot

    def with_admittance(
        self, trunk_admittance=None, branch_admittance: Mapping[str, object] | None = None
    ) -> "BranchNetwork":
        """A copy with a modulated A_trunk and/or branch admittances (freezing = 0)."""
        return BranchNetwork(
            self.trunk_joints,
            self.branches,
            self.trunk_admittance if trunk_admittance is None else trunk_admittance,
            {**self.branch_admittance, **(branch_admittance or {})},
        )
