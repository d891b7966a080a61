"""``icub param list|get|set|dump``: a node's parameters (what ``ros2 param`` does).

    icub param list /impedance_controller
    icub param get /sim_bridge mode
    icub param set /sim_bridge real_time_factor 0.5
    icub param set /impedance_controller stiffness_scale 2      # 2 -> 2.0 for a double
    icub param set /wrench_estimator contact_force_on 4.0
    icub param dump /sim_bridge > my_sim_bridge.yaml             # a --params-file

VALUE is YAML, as in ``ros2 param set`` (``true``, ``3``, ``0.5``, ``[1.0, 2.0]``, text);
a number is converted to the parameter's declared type when it can be (an integer for a
double parameter), so ``set ... 2`` works where ``ros2 param set`` would refuse a type change.
A refused value prints the node's reason and exits 1.
"""

from __future__ import annotations

import argparse
from typing import Any

import yaml

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT

__all__ = ["register", "run", "to_parameter_value", "parameter_value_text"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``param`` subcommand with ``list``, ``get``, ``set`` and ``dump``."""
    p = sub.add_parser("param", help="list, get, set and dump node parameters (ros2 param)",
                       description=__doc__.split("\n\n", 1)[1],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    sp = p.add_subparsers(dest="param_command", metavar="{list,get,set,dump}")
    p.set_defaults(func=lambda _a: (p.print_help(), 2)[1])

    def common(q: argparse.ArgumentParser) -> None:
        q.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                       help=f"wait this long for the node [s] (default {DISCOVERY_TIMEOUT:g})")

    q = sp.add_parser("list", help="names of a node's parameters (of every node if none given)")
    q.add_argument("node", nargs="?", help="node name, e.g. /sim_bridge")
    common(q)
    q.set_defaults(func=run)
    q = sp.add_parser("get", help="a parameter's value")
    q.add_argument("node")
    q.add_argument("name")
    common(q)
    q.set_defaults(func=run)
    q = sp.add_parser("set", help="set a parameter (YAML value)")
    q.add_argument("node")
    q.add_argument("name")
    q.add_argument("value", help="YAML value: true, 3, 0.5, [1.0, 2.0], text")
    common(q)
    q.set_defaults(func=run)
    q = sp.add_parser("dump", help="every parameter of a node as a --params-file YAML")
    q.add_argument("node")
    common(q)
    q.set_defaults(func=run)


# ---------------------------------------------------------------------- values
_ARRAY_FIELDS = {6: "bool_array_value", 7: "integer_array_value", 8: "double_array_value",
                 9: "string_array_value", 5: "byte_array_value"}
_SCALAR_FIELDS = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value"}
_TYPE_NAMES = {0: "not set", 1: "bool", 2: "integer", 3: "double", 4: "string",
               5: "byte array", 6: "bool array", 7: "integer array", 8: "double array",
               9: "string array"}


def parameter_value_to_python(pv: Any) -> Any:
    """The Python value of an rcl_interfaces/ParameterValue (arrays as lists)."""
    if pv.type in _SCALAR_FIELDS:
        return getattr(pv, _SCALAR_FIELDS[pv.type])
    if pv.type in _ARRAY_FIELDS:
        v = getattr(pv, _ARRAY_FIELDS[pv.type])
        return [bytes(b).hex() if isinstance(b, bytes) else b for b in v] if pv.type == 5 \
            else list(v)
    return None


def parameter_value_text(pv: Any) -> str:
    """ros2param's one-line rendering: 'Double value is: 0.5', 'String values are: [...]'."""
    label = {1: "Boolean value is", 2: "Integer value is", 3: "Double value is",
             4: "String value is", 5: "Byte values are", 6: "Boolean values are",
             7: "Integer values are", 8: "Double values are", 9: "String values are"}
    if pv.type not in label:
        return "Parameter not set."
    return f"{label[pv.type]}: {parameter_value_to_python(pv)}"


def to_parameter_value(text: str, current_type: int = 0) -> Any:
    """A ParameterValue from the YAML ``text``, converted to ``current_type`` (the declared
    type, ParameterType code; 0 = unknown: guessed as ros2param does) where lossless: an
    integer for a double, a list of numbers for a double array. Raises ValueError when the
    text is not valid YAML."""
    from rcl_interfaces.msg import ParameterType, ParameterValue
    from rclpy.parameter import get_parameter_value

    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ValueError(f"value {text!r} is not valid YAML: {exc}") from None
    pv = ParameterValue()
    num = (int, float)
    if current_type == ParameterType.PARAMETER_DOUBLE and isinstance(value, num) \
            and not isinstance(value, bool):
        pv.type, pv.double_value = current_type, float(value)
        return pv
    if current_type == ParameterType.PARAMETER_DOUBLE_ARRAY and isinstance(value, list) and \
            all(isinstance(v, num) and not isinstance(v, bool) for v in value):
        pv.type, pv.double_array_value = current_type, [float(v) for v in value]
        return pv
    if current_type == ParameterType.PARAMETER_STRING and value is not None and \
            not isinstance(value, (list, dict)):
        pv.type, pv.string_value = current_type, text  # "1.0" for a string stays text
        return pv
    return get_parameter_value(text)


# ---------------------------------------------------------------------- commands
def run(args: argparse.Namespace) -> int:
    """Dispatch to list / get / set / dump."""
    from icub_pmp.cli.session import cli_node

    with cli_node("icub_param") as (node, executor):
        if args.param_command == "list":
            return _list(node, executor, args)
        target = _node_name(args.node)
        if args.param_command == "get":
            pv = _get(node, executor, target, [args.name], args.timeout)[0]
            print(parameter_value_text(pv))
            return 0 if pv.type else 1
        if args.param_command == "set":
            return _set(node, executor, target, args)
        return _dump(node, executor, target, args.timeout)


def _node_name(name: str) -> str:
    return name if name.startswith("/") else "/" + name


def _call(node, executor, service: str, srv_type: Any, request: Any, timeout: float,
          server: str) -> Any:
    from icub_pmp.cli.session import spin_until, spin_until_ready

    client = node.create_client(srv_type, service)
    spin_until_ready(node, executor, client.service_is_ready, timeout, service, "service",
                     server)
    future = client.call_async(request)
    if not spin_until(executor, future.done, max(timeout, 10.0)):
        raise TimeoutError(f"service {service} gave no answer")
    return future.result()


def _list_names(node, executor, target: str, timeout: float) -> list[str]:
    from rcl_interfaces.srv import ListParameters

    res = _call(node, executor, f"{target}/list_parameters", ListParameters,
                ListParameters.Request(), timeout, target)
    return sorted(res.result.names)


def _get(node, executor, target: str, names: list[str], timeout: float) -> list[Any]:
    from rcl_interfaces.srv import GetParameters

    res = _call(node, executor, f"{target}/get_parameters", GetParameters,
                GetParameters.Request(names=names), timeout, target)
    return list(res.values)


def _list(node, executor, args: argparse.Namespace) -> int:
    from icub_pmp.cli.session import spin_until

    if args.node:
        targets = [_node_name(args.node)]
    else:  # every node offering parameters, after a discovery round
        spin_until(executor, lambda: False, min(args.timeout, 3.0))
        own = node.get_fully_qualified_name()
        targets = sorted(n for n in node.get_fully_qualified_node_names() if n != own)
    for target in targets:
        print(f"{target}:")
        for name in _list_names(node, executor, target, args.timeout):
            print(f"  {name}")
    return 0


def _set(node, executor, target: str, args: argparse.Namespace) -> int:
    from rcl_interfaces.msg import Parameter
    from rcl_interfaces.srv import SetParameters

    current = _get(node, executor, target, [args.name], args.timeout)[0]
    pv = to_parameter_value(args.value, current.type)
    res = _call(node, executor, f"{target}/set_parameters", SetParameters,
                SetParameters.Request(parameters=[Parameter(name=args.name, value=pv)]),
                args.timeout, target)
    r = res.results[0]
    if r.successful:
        print("Set parameter successful")
        return 0
    declared = f" (declared {_TYPE_NAMES.get(current.type, current.type)}, given " \
               f"{_TYPE_NAMES.get(pv.type, pv.type)})" if current.type != pv.type else ""
    print(f"Setting parameter failed: {r.reason}{declared}")
    return 1


def _dump(node, executor, target: str, timeout: float) -> int:
    names = _list_names(node, executor, target, timeout)
    values = _get(node, executor, target, names, timeout)
    params = {n: parameter_value_to_python(v) for n, v in zip(names, values) if v.type}
    print(yaml.safe_dump({f"/**{target}" if target.count("/") == 1 else target:
                          {"ros__parameters": params}}, sort_keys=False), end="")
    return 0
