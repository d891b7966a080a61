"""A stopped node's log file is removed (benchmarks start hundreds of nodes), its output kept."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from icub_pmp.graph import NodeProcess


def _proc() -> NodeProcess:
    return NodeProcess(command=[sys.executable, "-c", "print('hello from the node')"])


def test_stopped_process_log_removed_output_kept(monkeypatch) -> None:
    monkeypatch.delenv("ICUB_PMP_KEEP_NODE_LOGS", raising=False)
    p = _proc()
    p.proc.wait(30)
    path = p.log_path
    assert Path(path).is_file()
    p.stop()
    p.close_log()
    assert not Path(path).exists()
    assert "hello from the node" in p.output()


def test_keep_node_logs_keeps_the_file(monkeypatch) -> None:
    monkeypatch.setenv("ICUB_PMP_KEEP_NODE_LOGS", "1")
    with _proc() as p:
        p.proc.wait(30)
    try:
        assert "hello from the node" in Path(p.log_path).read_text()
        assert "hello from the node" in p.output()
    finally:
        os.unlink(p.log_path)
