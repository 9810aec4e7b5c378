"""Rows for the one table of bench/peers.sh (issue 31), shared by the peer scripts.

A peer script calls `emit(...)` once per (workload, vclay configuration, peer) it measured.
When the environment variable VCLAY_PEERS_ROWS names a file, the row is appended to it as one
JSON line; otherwise nothing happens, so every script still runs alone exactly as before.
bench/peers_table.py turns the rows into the Markdown table of docs/performance.md.
Standard library only: the scripts run in different virtual environments.
"""

import json
import os
import platform


def emit(suite, workload, vclay, vclay_ms, peer, peer_ms, check):
    """Appends one comparison: times in milliseconds for the same work (lower is better),
    `check` a short statement of the accuracy check that preceded the timing."""
    path = os.environ.get("VCLAY_PEERS_ROWS")
    if not path:
        return
    row = {"suite": suite, "workload": workload, "vclay": vclay, "vclay_ms": float(vclay_ms),
           "peer": peer, "peer_ms": float(peer_ms), "check": check}
    with open(path, "a") as f:
        f.write(json.dumps(row) + "\n")


def cpu_name():
    """The CPU's model name as Linux reports it (or the platform's machine name)."""
    try:
        with open("/proc/cpuinfo") as fh:
            return next(l.split(":", 1)[1].strip() for l in fh if l.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()
