#!/usr/bin/env python3
"""Hold the domain_coordinator lock of a ROS_DOMAIN_ID while the parent process lives
(scripts/graph.sh).

The tests reserve their ROS_DOMAIN_ID by binding the TCP port ``PORT_BASE + id``
(``icub_pmp.graph.reserve_domain_id``, as ros2's domain_coordinator does): a graph started by
hand that holds the port of its domain is never given to a test, which would otherwise talk to
it. Usage: ``hold_domain_lock.py ID``. Prints ``held`` once the port is bound (or ``taken``,
with a warning on stderr, and exits when another process holds it); then waits until killed or
until its parent is gone (a graph.sh killed with SIGKILL leaves no lock behind). Runs in
scripts/env.sh (domain_coordinator's PORT_BASE, the one the tests use).
"""

import os
import socket
import sys
import time

from domain_coordinator.impl import PORT_BASE

domain = int(sys.argv[1])
parent = os.getppid()
lock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
try:
    lock.bind(("", PORT_BASE + domain))
except OSError:
    print(f"graph.sh: ROS_DOMAIN_ID={domain} is held by another process (a test session that "
          "started this graph holds it itself): that process's nodes see this graph",
          file=sys.stderr)
    print("taken", flush=True)
    sys.exit(0)
print("held", flush=True)
sys.stdout.close()
while os.getppid() == parent:
    time.sleep(0.5)
