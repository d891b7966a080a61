"""ConfigParameters (icub_pmp.ros.parameters): a node's configuration dataclasses as its ROS
parameters, validated at start-up and on every change (in-process node, no DDS peer)."""

from __future__ import annotations

import dataclasses

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter

from icub_pmp.config import ConfigBase
from icub_pmp.errors import ConfigError, InvalidInput
from icub_pmp.ros.parameters import ConfigParameters, attribute_descriptions


@dataclasses.dataclass(frozen=True)
class _Gains(ConfigBase):
    """Attributes:
    gain: proportional gain [N m/rad], a longer
        description on two lines.
    limits: joint limits [rad].
    """

    gain: float = 2.0
    limits: tuple[float, ...] = (-1.0, 1.0)

    def validate(self) -> None:
        if self.gain < 0:
            raise ConfigError(f"gain must be >= 0, got {self.gain}")


@dataclasses.dataclass(frozen=True)
class _Model(ConfigBase):
    name: str = "icub"
    rate_hz: float = 100.0


@pytest.fixture
def make_node(ros_domain_id):
    ctx = Context()
    rclpy.init(context=ctx, domain_id=ros_domain_id)
    nodes = []

    def make(overrides=()):
        node = Node("params_test", context=ctx, start_parameter_services=False,
                    parameter_overrides=[Parameter(k, value=v) for k, v in overrides])
        nodes.append(node)
        return node

    try:
        yield make
    finally:
        for n in nodes:
            n.destroy_node()
        rclpy.try_shutdown(context=ctx)


def _set(node, **values):
    return node.set_parameters_atomically([Parameter(k, value=v) for k, v in values.items()])


def test_every_field_is_a_parameter_with_its_default_and_description(make_node):
    node = make_node()
    params = ConfigParameters(node, (_Gains, _Model), read_only=("name",))
    assert node.get_parameter("gain").value == 2.0
    assert node.get_parameter("limits").value == [-1.0, 1.0]
    assert node.get_parameter("name").value == "icub"
    desc = node.describe_parameter("gain")
    assert desc.description == "proportional gain [N m/rad], a longer description on two lines."
    assert node.describe_parameter("name").read_only
    assert "config/params_test.yaml" in node.describe_parameter("rate_hz").description
    assert params.get(_Gains) == _Gains() and params.get(_Model) == _Model()


def test_start_up_values_are_validated(make_node):
    """A node started with a value its configuration refuses does not start (ConfigError)."""
    node = make_node([("gain", -1.0)])
    with pytest.raises(ConfigError, match="bad parameters: gain must be >= 0"):
        ConfigParameters(node, _Gains)


def test_a_bad_change_is_refused_and_the_configuration_kept(make_node):
    node = make_node()
    params = ConfigParameters(node, _Gains)
    result = _set(node, gain=-3.0)
    assert not result.successful and "gain must be >= 0" in result.reason
    assert params.config.gain == 2.0 and node.get_parameter("gain").value == 2.0
    result = _set(node, gain="high")
    assert not result.successful
    assert _set(node, gain=5.0).successful
    assert params.config.gain == 5.0


def test_read_only_fields_cannot_change(make_node):
    node = make_node()
    params = ConfigParameters(node, (_Gains, _Model), read_only=("name",))
    assert not _set(node, name="other").successful
    assert params.get(_Model).name == "icub"


def test_on_change_sees_old_new_and_changed_and_may_refuse(make_node):
    node = make_node()
    seen = []

    def on_change(old, new, changed):
        seen.append((old.gain, new.gain, changed))
        if new.gain > 10:
            raise InvalidInput(f"gain {new.gain} is more than the motor takes")

    params = ConfigParameters(node, _Gains, on_change=on_change)
    assert _set(node, gain=3.0, limits=[-1.0, 1.0]).successful
    assert seen == [(2.0, 3.0, frozenset({"gain"}))]
    result = _set(node, gain=20.0)
    assert not result.successful and "more than the motor takes" in result.reason
    assert params.config.gain == 3.0


def test_check_and_reject_hooks(make_node):
    """``check`` cross-checks the built configurations; ``reject`` sees every parameter of a
    request, fields or not."""
    node = make_node()

    def check(configs):
        gains, model = configs
        if gains.gain > model.rate_hz:
            raise ConfigError("gain above rate_hz")

    ConfigParameters(node, (_Gains, _Model), check=check,
                     reject=lambda p: "stay on wall time" if p.get("use_sim_time") else None)
    assert not _set(node, gain=200.0).successful
    assert _set(node, gain=200.0, rate_hz=300.0).successful
    result = _set(node, use_sim_time=True)
    assert not result.successful and result.reason == "stay on wall time"


def test_field_clash_and_unknown_read_only_are_errors(make_node):
    @dataclasses.dataclass(frozen=True)
    class Clash(ConfigBase):
        gain: float = 1.0

    with pytest.raises(ConfigError, match="gain"):
        ConfigParameters(make_node(), (_Gains, Clash))
    with pytest.raises(ConfigError, match="read_only"):
        ConfigParameters(make_node(), _Gains, read_only=("nope",))


def test_attribute_descriptions_of_a_class_without_the_section():
    assert attribute_descriptions(_Model) == {}
    assert set(attribute_descriptions(_Gains)) == {"gain", "limits"}
