"""JacobianSourceConfig and :func:`make_provider`: which body model PMP plans on.

``analytic``: the iCub URDF through pinocchio (:class:`PinocchioJacobianProvider`).
``learned``: the body networks learned from babbling (:class:`LearnedJacobianProvider`), one
model file per arm; an arm without a file cannot be planned for (its hand frame is unknown to
the learned provider).
"""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, ModelError
from icub_pmp.pmp.jacobian_provider import JacobianProvider

__all__ = ["JacobianSourceConfig", "make_provider", "JACOBIAN_SOURCES"]

JACOBIAN_SOURCES = ("analytic", "learned")


@dataclasses.dataclass(frozen=True)
class JacobianSourceConfig(ConfigBase):
    """Attributes:
        jacobian_source: ``analytic`` (URDF, pinocchio) | ``learned`` (body networks).
        learned_model_right: body network file (.npz) of the right arm ('' = none).
        learned_model_left: body network file (.npz) of the left arm ('' = none).
    """

    jacobian_source: str = "analytic"
    learned_model_right: str = ""
    learned_model_left: str = ""

    def validate(self) -> None:
        """A known source; ``learned`` needs at least one model file."""
        if self.jacobian_source not in JACOBIAN_SOURCES:
            raise ConfigError(f"jacobian_source: expected one of {JACOBIAN_SOURCES}, got "
                              f"{self.jacobian_source!r}")
        if self.jacobian_source == "learned" and not (self.learned_model_right
                                                      or self.learned_model_left):
            raise ConfigError("jacobian_source 'learned' needs learned_model_right and/or "
                              "learned_model_left (body network files from babbling)")


def make_provider(config: JacobianSourceConfig) -> JacobianProvider:
    """The body model ``config`` names (model files are loaded and checked: a missing file or a
    model of the other arm is a :class:`ConfigError` naming the file)."""
    if config.jacobian_source == "analytic":
        from icub_pmp.pmp.pinocchio_provider import PinocchioJacobianProvider

        return PinocchioJacobianProvider()
    from icub_pmp.body_schema.learned_jacobian_provider import LearnedJacobianProvider

    files = {arm: path for arm, path in (("right", config.learned_model_right),
                                         ("left", config.learned_model_left)) if path}
    try:
        return LearnedJacobianProvider.from_files(files)
    except ModelError as exc:
        raise ConfigError(f"jacobian_source learned: {exc}") from exc
