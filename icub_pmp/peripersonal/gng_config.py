"""GrowingNeuralGasConfig: the constants of the peripersonal-space growing neural gas.

The defaults are the paper's (Bhat and Mohan 2018, "Internal model for peripersonal space",
steps a-g): tau_e = 10, vigilance v = 0.25, sigma_e = 1, e_w = 0.04, e_n = 0.0006,
age_max = 25. The paper does not say in which unit its distances enter the error kernel;
``length_scale`` is that unit here (see :class:`GrowingNeuralGas`). Its default, 15 mm (a
neuron grows a neighbour for inputs beyond about 11 mm), was chosen for this project's goal:
held-out babbled hand positions within 2 cm of a neuron at least 98 % of the time. On the
iCub arm (7 joints uniform within their limits, a workspace about 0.7 m across) that took
40,000 babbles per arm and about 5,500 neurons (measured: 0.986 with 5,479 neurons; 10,000
babbles cover only 0.96 of held-out positions within 2 cm even with every babble kept).
The paper's maps of two industrial robots had 478 and 476 neurons from about 10,000 babbles.
"""

from __future__ import annotations

import dataclasses

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError

__all__ = ["GrowingNeuralGasConfig"]


@dataclasses.dataclass(frozen=True)
class GrowingNeuralGasConfig(ConfigBase):
    """Growing neural gas constants (units in the field comments)."""

    tau_e: float = 10.0  # time constant of the error low-pass filter [inputs]
    vigilance: float = 0.25  # error threshold v above which a neuron is added [-]
    sigma_e: float = 1.0  # width of the error kernel [length_scale units]
    e_w: float = 0.04  # learning rate of the winner [-]
    e_n: float = 0.0006  # learning rate of the winner's neighbours [-]
    age_max: int = 25  # lateral connections older than this are pruned [inputs]
    length_scale: float = 0.015  # one kernel unit [m]: distances are divided by it
    max_epochs: int = 8  # passes over the babbling data at most
    min_growth: float = 0.01  # stop when a pass adds fewer neurons than this fraction [-]
    max_neurons: int = 20000  # hard cap on the map size [-]
    seed: int = 0  # random initialisation and input order

    def validate(self) -> None:
        """Range checks (raise :class:`ConfigError` naming the field)."""
        for name in ("tau_e", "sigma_e", "length_scale"):
            if not getattr(self, name) > 0.0:
                raise ConfigError(f"GrowingNeuralGasConfig.{name}: expected > 0, got "
                                  f"{getattr(self, name)}")
        if not 0.0 < self.vigilance < 1.0:
            raise ConfigError(f"GrowingNeuralGasConfig.vigilance: expected in (0, 1), got "
                              f"{self.vigilance}")
        for name in ("e_w", "e_n", "min_growth"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ConfigError(f"GrowingNeuralGasConfig.{name}: expected in [0, 1], got "
                                  f"{getattr(self, name)}")
        for name in ("age_max", "max_epochs"):
            if getattr(self, name) < 1:
                raise ConfigError(f"GrowingNeuralGasConfig.{name}: expected >= 1, got "
                                  f"{getattr(self, name)}")
        if self.max_neurons < 2:
            raise ConfigError(f"GrowingNeuralGasConfig.max_neurons: expected >= 2, got "
                              f"{self.max_neurons}")
