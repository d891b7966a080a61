#!/usr/bin/env python3
"""Repair the ROS 2 wheels' exported CMake files for this interpreter (idempotent).

The ros-jazzy-* wheels were built under /opt/python/cp311-cp311; their exported CMake files
name that interpreter's include dir and numpy's include dir. CMake's generate step fails on the
missing paths until they point at this interpreter.
"""

from __future__ import annotations

import sys
import sysconfig
from pathlib import Path

import numpy

OLD_PY_INCLUDE = "/opt/python/cp311-cp311/include/python3.11"
OLD_NUMPY_INCLUDE = "/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"


def main() -> int:
    prefix = Path(sys.prefix)
    new_py = sysconfig.get_paths()["include"]
    new_np = numpy.get_include()
    changed = 0
    for f in (prefix / "share").glob("*/cmake/*.cmake"):
        text = f.read_text(errors="surrogateescape")
        if OLD_PY_INCLUDE not in text and OLD_NUMPY_INCLUDE not in text:
            continue
        text = text.replace(OLD_NUMPY_INCLUDE, new_np).replace(OLD_PY_INCLUDE, new_py)
        f.write_text(text, errors="surrogateescape")
        changed += 1
    print(f"fix_wheel_cmake: {changed} file(s) repaired under {prefix}/share")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
