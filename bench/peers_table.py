#!/usr/bin/env python3
"""Writes the one peer table of bench/peers.sh into docs/performance.md (issue 31).

Usage: peers_table.py RUN_DIR DOC

RUN_DIR is the folder bench/peers.sh filled for one run: for each suite it ran, NAME.rows (the
JSON lines of bench/peers_rows.py), NAME.log, NAME.rc, NAME.date and NAME.yard_start /
NAME.yard_end (the JSON lines of `cargo run --release -p vclay-core --example yardstick`).
The rows of the suites this run measured replace those suites' rows in bench/peers.json (the
last measured rows of every suite, kept in the repository); suites not run keep their earlier
rows, each with its own date, yardstick and load. The table of all of them replaces the text
between BEGIN and END in DOC. A suite that said SKIPPED or failed gets one row that says so and
why. Standard library only.
"""

import json
import os
import sys

from peers_rows import cpu_name

BEGIN = "<!-- bench/peers.sh table: begin (generated; do not edit by hand) -->"
END = "<!-- bench/peers.sh table: end -->"
HERE = os.path.dirname(os.path.abspath(__file__))
STORE = os.path.join(HERE, "peers.json")
# Suites in table order, with what a skipped or failed suite's row names.
SUITES = {
    "eval": ("surface evaluation (bench/compare.py)", "OpenNURBS (rhino3dm), geomdl"),
    "solids": ("mass-spring step (bench/solids_peers.sh)", "Taichi, NVIDIA Warp (CPU)"),
    "ffd": ("1M-vertex FFD (bench/ffd_peers.py)", "PyGeM FFD"),
    "fit": ("scan fitting (bench/check_fit.sh)", "SciPy FITPACK, geomdl"),
}


def machine():
    return f"{cpu_name()}, {os.cpu_count()} CPUs"


def read(path, default=None):
    try:
        with open(path) as fh:
            return fh.read().strip()
    except OSError:
        return default


def suite_result(run, name):
    """The rows of one suite of this run, each with the run's context; None when not run."""
    rc = read(os.path.join(run, name + ".rc"))
    if rc is None:
        return None
    yard = [json.loads(read(os.path.join(run, f"{name}.yard_{e}"), "{}") or "{}")
            for e in ("start", "end")]
    context = {
        "suite": name,
        "date": read(os.path.join(run, name + ".date"), "?"),
        "machine": machine(),
        "yardstick_ms": [y.get("ms") for y in yard],
        "yardstick_version": yard[0].get("version"),
        "load1": [y.get("load1") for y in yard],
    }
    rows = [json.loads(l) for l in (read(os.path.join(run, name + ".rows"), "") or "").splitlines()
            if l.strip()]
    log = (read(os.path.join(run, name + ".log"), "") or "").splitlines()
    status = None
    if rc != "0":
        tail = next((l for l in reversed(log) if l.strip()), "no output")
        status = f"FAILED (exit {rc}): {tail.strip()[:200]}"
    elif not rows:
        why = next((l for l in reversed(log) if "SKIPPED" in l), "the script measured nothing")
        status = why.strip()[:300]
    if status:
        what, peers = SUITES[name]
        rows = [{"workload": what, "vclay": "-", "vclay_ms": None, "peer": peers,
                 "peer_ms": None, "check": status}]
    return [{**context, **r, "suite": name} for r in rows]


def fmt_ms(x):
    if x is None:
        return "-"
    return f"{x:.3f}" if x < 1 else f"{x:.1f}" if x < 1000 else f"{x:,.0f}"


def pair(v, digits):
    if not v or any(x is None for x in v):
        return "-"
    return " / ".join(f"{x:.{digits}f}" for x in v)


def table(rows):
    out = [
        "| workload | vclay | vclay ms | peer | peer ms | peer / vclay | accuracy check | "
        "yardstick ms (start / end) | load (start / end) | date (UTC) | machine |",
        "| --- | --- | ---: | --- | ---: | ---: | --- | ---: | ---: | --- | --- |",
    ]
    for r in rows:
        v, p = r.get("vclay_ms"), r.get("peer_ms")
        ratio = f"{p / v:.1f}x" if v and p and v > 0 else "-"
        cells = [r["workload"], r["vclay"], fmt_ms(v), r["peer"], fmt_ms(p), ratio, r["check"],
                 pair(r.get("yardstick_ms"), 2), pair(r.get("load1"), 1), r["date"], r["machine"]]
        out.append("| " + " | ".join(str(c).replace("|", "/") for c in cells) + " |")
    return "\n".join(out)


def main():
    run, doc = sys.argv[1], sys.argv[2]
    stored = json.loads(read(STORE, "{}") or "{}")
    for name in SUITES:
        res = suite_result(run, name)
        if res is not None:
            stored[name] = res
    with open(STORE + ".tmp", "w") as fh:
        json.dump(stored, fh, indent=1)
        fh.write("\n")
    os.replace(STORE + ".tmp", STORE)
    rows = [r for name in SUITES for r in stored.get(name, [])]
    text = read(doc, "")
    if BEGIN not in text or END not in text:
        sys.exit(f"peers_table: {doc} lacks the markers {BEGIN} ... {END}")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    block = "\n".join([
        BEGIN,
        "Times in ms for the same work (lower is better); peer / vclay > 1 means vclay is faster. "
        "The yardstick (`vclay_core::yardstick`, one thread) and the 1-minute load average are "
        "taken before and after each script: compare rows through them, not across dates. "
        "Details: bench/results.md, bench/solids_peers.md, bench/ffd_peers.md, bench/peers.json "
        "and the logs under target/peers/.",
        "",
        table(rows),
        END,
    ])
    with open(doc + ".tmp", "w") as fh:
        fh.write(head + block + tail)
    os.replace(doc + ".tmp", doc)
    print(table(rows))


if __name__ == "__main__":
    main()
