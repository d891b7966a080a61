"""``icub graph``: the nodes, topics (with types) and services (with types) of the domain."""

from __future__ import annotations

import argparse

from icub_pmp.cli.session import cli_node, spin_until

__all__ = ["register", "run"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``graph`` subcommand."""
    p = sub.add_parser("graph", help="list nodes, topics and services")
    p.add_argument("--wait", type=float, default=3.0, help="discovery time [s] (default 3)")
    p.add_argument(
        "--all", action="store_true", help="also list parameter/type-description services"
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Discover for ``--wait`` seconds, then print the graph."""
    if args.wait < 0:
        raise ValueError(f"--wait must be >= 0, got {args.wait}")
    with cli_node("icub_graph") as (node, executor):
        spin_until(executor, lambda: False, args.wait)
        own = node.get_fully_qualified_name()
        nodes = sorted(n for n in node.get_fully_qualified_node_names() if n != own)
        topics = sorted(node.get_topic_names_and_types())
        services = sorted(node.get_service_names_and_types())
    hidden = ("/describe_parameters", "/get_parameter_types", "/get_parameters",
              "/list_parameters", "/set_parameters", "/set_parameters_atomically",
              "/get_type_description")
    if not args.all:
        services = [(n, t) for n, t in services if not n.endswith(hidden)]
        topics = [(n, t) for n, t in topics if n not in ("/rosout", "/parameter_events")]
    print(f"Nodes ({len(nodes)}):")
    for n in nodes:
        print(f"  {n}")
    print(f"Topics ({len(topics)}):")
    for n, types in topics:
        print(f"  {n} [{', '.join(types)}]")
    print(f"Services ({len(services)}):")
    for n, types in services:
        print(f"  {n} [{', '.join(types)}]")
    return 0
