"""Scales of the eq 11 NLP's constraints (shared by :class:`IkProblem` and :class:`IkSeed`).

The squared position error is bounded in cm^2 and the lifted equality ``x_d - K_x(q) - s = 0``
is written in cm inside the NLP, so that IPOPT's absolute ``constr_viol_tol`` is meaningful.
"""

__all__ = ["POSITION_SCALE", "SLACK_SCALE"]

POSITION_SCALE = 1e4  # m^2 -> cm^2 for the bound on the squared position error inside the NLP
SLACK_SCALE = 1e2  # m -> cm for the equality x_d - K_x(q) - s = 0 inside the NLP
