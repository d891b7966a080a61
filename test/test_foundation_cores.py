"""Dependencies point one way.

1. Cores import no ROS: the numerical packages load in a fresh interpreter without pulling in
   rclpy or any generated message module.
2. The import graph of ``icub_pmp`` and ``icub_sim_bridge`` (read from the sources with
   ``ast``, lazy imports inside functions included) has no cycle, between packages or between
   modules, and no import goes up the layers: cores -> ROS adapters (``ros``, ``graph``) ->
   executables (``nodes``, ``cli``, the simulator's ``*_node``) -> ``demo`` -> ``testing``;
   no module of ``icub_pmp`` below the demo imports the simulator package.

Every package of ``icub_pmp`` that is not a known adapter package is a core, so new packages
are covered without being listed here.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import icub_pmp
from icub_pmp.config import repo_root

PACKAGES = ("icub_pmp", "icub_sim_bridge")
#: layer of the adapter packages of icub_pmp (every other package is a core, layer 0)
ADAPTER_LAYERS = {
    "icub_pmp.ros": 1,
    "icub_pmp.graph": 1,
    "icub_pmp.nodes": 2,
    "icub_pmp.cli": 2,
    "icub_pmp.demo": 3,
    "icub_pmp.paper": 3,  # the paper report runs experiments on the simulator harness
    "icub_pmp.testing": 4,
}
SIM_HARNESS = "icub_sim_bridge.harness"  # test and benchmark support: layer 1
NODE_SUFFIX = "_node"  # a ROS node module inside a core package: layer 2
LAYER_NAMES = {0: "core", 1: "adapter", 2: "executable", 3: "demo", 4: "testing"}
ROS_PREFIXES = ("rclpy", "rosidl_runtime_py")


# ---------------------------------------------------------------------------- the graph
def module_files(root: Path) -> dict[str, Path]:
    """{module name: file} of every module of the two packages under ``root``."""
    out = {}
    for pkg in PACKAGES:
        for path in sorted((root / pkg).rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


def import_edges(root: Path) -> dict[str, set[str]]:
    """{module: modules of the two packages it imports} (``from p import m`` of a module
    ``p.m`` counts as importing ``p.m``; relative imports resolved)."""
    files = module_files(root)
    edges: dict[str, set[str]] = {}
    for mod, path in files.items():
        is_pkg = path.name == "__init__.py"
        targets: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = mod.split(".")[: len(mod.split(".")) - node.level + is_pkg]
                    base = ".".join(anchor + ([base] if base else []))
                names = [f"{base}.{a.name}" if f"{base}.{a.name}" in files else base
                         for a in node.names]
            else:
                continue
            for name in names:
                while name and name not in files:  # `import a.b.c` of a package a.b
                    name = name.rpartition(".")[0]
                if name and name != mod:
                    targets.add(name)
        edges[mod] = targets
    return edges


def layer(mod: str) -> int:
    """Layer of a module (module doc)."""
    for prefix, rank in ADAPTER_LAYERS.items():
        if mod == prefix or mod.startswith(prefix + "."):
            return rank
    if mod == SIM_HARNESS or mod.startswith(SIM_HARNESS + "."):
        return 1
    if mod.rpartition(".")[2].endswith(NODE_SUFFIX):
        return 2
    return 0


def package_of(mod: str) -> str:
    """The package a module belongs to in the package-level graph: ``icub_pmp.<sub>`` (a
    top-level module is its own), the simulator's harness, node modules on their own, the
    rest of ``icub_sim_bridge``."""
    parts = mod.split(".")
    if parts[0] == "icub_pmp":
        return ".".join(parts[:2])
    if mod.startswith(SIM_HARNESS):
        return SIM_HARNESS
    return mod if layer(mod) == 2 else "icub_sim_bridge"


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one member (Tarjan), each a cycle."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10000))
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def package_edges(edges: dict[str, set[str]]) -> dict[str, set[str]]:
    """The package-level graph of a module graph."""
    out: dict[str, set[str]] = {}
    for a, targets in edges.items():
        pa = package_of(a)
        out.setdefault(pa, set()).update(package_of(b) for b in targets if package_of(b) != pa)
    return out


def upward_imports(edges: dict[str, set[str]]) -> list[str]:
    """Imports that go up the layers, and imports of the simulator by icub_pmp below the demo."""
    bad = []
    for a, targets in sorted(edges.items()):
        for b in sorted(targets):
            if layer(b) > layer(a):
                bad.append(f"{a} ({LAYER_NAMES[layer(a)]}) imports {b} ({LAYER_NAMES[layer(b)]})")
            elif (a.startswith("icub_pmp") and b.startswith("icub_sim_bridge")
                  and layer(a) < ADAPTER_LAYERS["icub_pmp.demo"]):
                bad.append(f"{a} ({LAYER_NAMES[layer(a)]}) imports the simulator: {b}")
    return bad


# ---------------------------------------------------------------------------- tests
def test_import_graph_has_no_cycle_and_no_upward_import():
    """No cycle between packages or modules; no core imports an adapter, an executable, the
    demo, test support or the simulator (module doc)."""
    edges = import_edges(repo_root())
    assert "icub_pmp.kinematics.robot_model" in edges and "icub_pmp.ros.conversions" in edges
    assert layer("icub_pmp.pmp.pmp_planner") == 0 and layer("icub_pmp.nodes.pmp_planner") == 2
    assert layer("icub_sim_bridge.sim_bridge_node") == 2 and layer("icub_sim_bridge.simulator") == 0
    assert cycles(package_edges(edges)) == []
    assert cycles(edges) == []
    assert upward_imports(edges) == []


def test_the_checks_find_what_they_look_for():
    """The analysis itself: a cycle and an upward import in a made-up graph are reported."""
    edges = {
        "icub_pmp.pmp.a": {"icub_pmp.pmp.b"},
        "icub_pmp.pmp.b": {"icub_pmp.pmp.a", "icub_pmp.ros.conversions"},
        "icub_pmp.body_schema.c": {"icub_sim_bridge.simulator"},
        "icub_pmp.ros.conversions": set(),
    }
    assert cycles(edges) == [["icub_pmp.pmp.a", "icub_pmp.pmp.b"]]
    assert len(upward_imports(edges)) == 2
    assert cycles(package_edges(edges)) == []


def core_modules() -> list[str]:
    """Every module of layer 0 (cores of icub_pmp and of the simulator) and the harness."""
    return sorted(m for m in module_files(repo_root())
                  if layer(m) == 0 or m.startswith(SIM_HARNESS))


def test_cores_do_not_import_ros():
    """Importing every core module loads no rclpy, rosidl or *_msgs/*_srvs module."""
    mods = core_modules()
    assert "icub_pmp.kinematics.robot_model" in mods and "icub_pmp.errors" in mods
    code = (
        "import importlib, sys\n"
        f"for m in {mods!r}: importlib.import_module(m)\n"
        f"bad = sorted(m for m in sys.modules if m.split('.')[0] in {ROS_PREFIXES!r}"
        " or m.split('.')[0].endswith(('_msgs', '_srvs', '_interfaces')))\n"
        "print('ROS_MODULES', bad)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=repo_root(), timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "ROS_MODULES []" in out.stdout, out.stdout
    assert icub_pmp.__version__


def test_reserve_domain_id_avoids_the_shells_domain(monkeypatch):
    """The domain a graph started by hand uses (the shell's ROS_DOMAIN_ID, 42 from
    scripts/env.sh) is never reserved for a test, even when the search starts right before it:
    a test there would talk to that graph."""
    import random

    from icub_pmp.graph import ros_domain

    monkeypatch.setattr(ros_domain, "_SHELL_DOMAIN", "42")
    monkeypatch.setenv("ROS_DOMAIN_ID", "57")
    for start in (40, 55):  # the first candidate is start + 2: the shell's, then the env's
        monkeypatch.setattr(random, "randrange", lambda n, s=start: s)
        with ros_domain.reserve_domain_id() as did:
            assert did not in (42, 57) and 1 <= did <= 100


def test_reserve_domain_id_lets_the_callers_errors_through():
    """An OSError raised inside ``reserve_domain_id`` (a TimeoutError: a node that did not
    answer) reaches the caller as itself, not as domain_coordinator's "generator didn't stop
    after throw()"; the domain is free again afterwards, and two reservations differ."""
    import socket

    import pytest
    from domain_coordinator.impl import PORT_BASE

    from icub_pmp.graph import reserve_domain_id

    with pytest.raises(TimeoutError, match="no answer"):
        with reserve_domain_id() as did:
            raise TimeoutError("no answer")
    probe = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        probe.bind(("", PORT_BASE + did))  # released
    finally:
        probe.close()
    with reserve_domain_id() as a, reserve_domain_id() as b:
        assert a != b and 1 <= a <= 100 and 1 <= b <= 100
