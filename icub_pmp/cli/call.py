"""``icub call SERVICE [TYPE] [VALUES]``: call a service once and print the response (what
``ros2 service call`` does).

    icub call /sim/reset "{posture: rest}"
    icub call /sim/apply_wrench icub_interfaces/srv/ApplyWrench \\
        "{target: r_hand_dh_frame, wrench: {force: {z: -5.0}}, duration: 1.0}"
    icub call /sim/set_paused std_srvs/srv/SetBool "{data: true}"
    icub call /impedance_controller/hold

VALUES is the request in ros2cli's YAML syntax (fields not named keep their defaults); the
type is read from the graph when it is not given. The response is printed as one YAML
document (``response: {...}``). A bad
field name or value exits with a one-line error naming the field, before anything is sent.
"""

from __future__ import annotations

import argparse
import sys

import yaml

from icub_pmp.cli.defaults import DISCOVERY_TIMEOUT

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``call`` subcommand."""
    p = sub.add_parser(
        "call", help="call a service (ros2 service call)",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("service", help="service name, e.g. /sim/reset")
    p.add_argument("args", nargs="*", metavar="[TYPE] [VALUES]",
                   help="service type (pkg/srv/Type; default: from the graph) and the request "
                        "in YAML (default: {})")
    p.add_argument("--timeout", type=float, default=DISCOVERY_TIMEOUT,
                   help=f"wait this long for the server [s] (default {DISCOVERY_TIMEOUT:g})")
    p.add_argument("--response-timeout", type=float, default=60.0,
                   help="wait this long for the answer once sent [s] (default 60)")
    p.set_defaults(func=run, extra_positionals="args")


def run(args: argparse.Namespace) -> int:
    """Validate the request, wait for the server, call once, print the response."""
    from icub_pmp.cli.session import cli_node, connect_typed, spin_until, typed_values
    from icub_pmp.ros.msg_types import message_to_dict

    typed = typed_values(args.service, args.args, "service")
    service = typed.name
    with cli_node("icub_call") as (node, executor):
        client = connect_typed(node, executor, typed,
                               lambda srv: node.create_client(srv, service), args.timeout)
        request = typed.message
        print(f"requester: making request: {request!r}", file=sys.stderr)
        future = client.call_async(request)
        if not spin_until(executor, future.done, args.response_timeout):
            raise TimeoutError(f"service {service} gave no answer within "
                               f"{args.response_timeout:g} s")
        response = future.result()
    # one YAML document: {response: {...}}
    sys.stdout.write(yaml.safe_dump({"response": message_to_dict(response, None)},
                                    sort_keys=False))
    return 0
