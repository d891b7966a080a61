"""Compile CasADi NLPs and functions to C once and reuse them: ``compiled_nlpsol``,
``compiled_function``.

CasADi's documented code-generation route: ``solver.generate_dependencies('nlp.c')`` writes the
objective, constraints, their derivatives and the exact Lagrangian Hessian as C; gcc turns it
into a shared library; ``nlpsol(name, 'ipopt', 'nlp.so', opts)`` loads it. The library is
cached under ``$ICUB_PMP_CACHE`` (default ``~/.cache/icub_pmp``) in ``casadi/``, named by a hash
of the generated C, so a changed model or formulation can never pick up a stale library.
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Callable

import casadi as ca

__all__ = ["compiled_function", "compiled_nlpsol", "cache_dir"]

_LOG = logging.getLogger(__name__)
_CFLAGS = ("-O2", "-fPIC", "-shared")


def cache_dir() -> Path:
    """Folder of the compiled NLP libraries (created on demand)."""
    root = os.environ.get("ICUB_PMP_CACHE")
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        root = str(Path(base) / "icub_pmp")
    return Path(root) / "casadi"


def compiled_nlpsol(
    name: str, nlp: dict, opts: dict, *more_opts: dict
) -> tuple[list[ca.Function], bool]:
    """IPOPT solvers of ``nlp``, one per option set (``opts``, then ``more_opts``), all backed
    by the same compiled C when gcc is available.

    Returns ``([solver, ...], compiled)``; falls back to CasADi's SX virtual machine (same
    results, slower) when the compiler is missing or fails, logging why.
    """
    plain = ca.nlpsol(name, "ipopt", nlp, opts)
    lib = _compile(name, plain.generate_dependencies)
    if lib is None:
        return [plain] + [ca.nlpsol(name, "ipopt", nlp, o) for o in more_opts], False
    return [ca.nlpsol(name, "ipopt", str(lib), o) for o in (opts, *more_opts)], True


def compiled_function(fn: ca.Function) -> tuple[ca.Function, bool]:
    """``fn`` as compiled C (``ca.external`` of the cached library) when gcc is available;
    otherwise ``fn`` itself (CasADi's virtual machine). Returns ``(function, compiled)``."""
    lib = _compile(fn.name(), lambda c_name: fn.generate(c_name))
    if lib is None:
        return fn, False
    return ca.external(fn.name(), str(lib)), True


def _compile(name: str, write_c: Callable[[str], object]) -> Path | None:
    """Write C with ``write_c(file_name)`` (into a temporary folder) and compile it, cached by
    the hash of the source; None (logged) when there is no compiler or it fails."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        _LOG.warning("no C compiler found: %s runs without code generation", name)
        return None
    try:
        with tempfile.TemporaryDirectory() as tmp:
            c_file = Path(tmp) / f"{name}.c"
            cwd = os.getcwd()
            os.chdir(tmp)  # CasADi's generators write into the current folder
            try:
                write_c(c_file.name)
            finally:
                os.chdir(cwd)
            source = c_file.read_bytes()
            digest = hashlib.sha256(source + " ".join(_CFLAGS).encode()).hexdigest()[:16]
            out_dir = cache_dir()
            out_dir.mkdir(parents=True, exist_ok=True)
            lib = out_dir / f"{name}_{digest}.so"
            if not lib.exists():
                part = out_dir / f".{lib.name}.{os.getpid()}.part"
                subprocess.run(
                    [cc, *_CFLAGS, str(c_file), "-o", str(part), "-lm"],
                    check=True,
                    capture_output=True,
                    timeout=300,
                )
                os.replace(part, lib)  # atomic: concurrent builders never see half a file
        return lib
    except (OSError, subprocess.SubprocessError, RuntimeError) as exc:
        detail = getattr(exc, "stderr", b"") or b""
        _LOG.warning(
            "code generation for %s failed (%s %s): running without it",
            name,
            exc,
            detail.decode(errors="replace")[:500],
        )
        return None
