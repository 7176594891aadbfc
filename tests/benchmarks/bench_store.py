"""Where the benchmark scripts store what they measured: ``docs/data/bench_<name>.json``.

The validation report (``docs/validation.md.in``) reads the medians from these files with
``{{json:bench_<name>.json#...:spec|not measured}}``; a benchmark never run on this checkout
renders as "not measured". Each file holds the parameters of the run, the measured times (all
runs, their minimum and median), the targets, the machine (:func:`machine`) and the provenance
(:func:`lubrication.io.provenance`). Files are written atomically (a temporary file renamed
over the target, :func:`lubrication.io.write_json`), so an interrupted benchmark leaves the
previous file intact.

Timings depend on the machine and on what else runs on it: :func:`machine` records the load
average before and after the run and states "machine loaded" when other processes were
running at the start (1-minute load average of at least :data:`LOADED` before the clock
starts). The load average decays over minutes, so right after another benchmark it still
counts that one: "loaded" is then an overstatement, never an understatement.
"""

from __future__ import annotations

import json
import os
import platform
import sys
from pathlib import Path

from lubrication.io import provenance, write_json

DATA = Path(__file__).resolve().parents[2] / "docs" / "data"
LOADED = 0.5          # 1-min load average before the run above which the machine was shared


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine(load_before: tuple[float, float, float] | None = None) -> dict:
    """The machine of a run: CPU model, cores usable by this process, OS, the load average
    (1, 5, 15 min) before the run (``load_before``, taken by the caller before the clock
    started) and after it, and ``state``: "machine loaded" if the 1-minute load average before
    the run was at least :data:`LOADED` (other jobs were running), else "machine idle"."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    now = os.getloadavg()
    before = load_before if load_before is not None else now
    return {"cpu": _cpu_model(), "cores": cores, "system": platform.platform(terse=True),
            "load_before": [round(x, 2) for x in before], "load_after": [round(x, 2) for x in now],
            "state": "machine loaded" if before[0] >= LOADED else "machine idle"}


def store(name: str, doc: dict, *, merge: str | None = None) -> Path:
    """Write ``doc`` (plus ``machine`` if absent, and ``provenance``) to
    ``docs/data/bench_<name>.json`` atomically; returns the path.

    With ``merge``, ``doc[merge]`` is a dict of entries (e.g. the cases of
    ``bench_vesicle.py``) that replaces only the same entries of the existing file, so cases
    run one at a time accumulate; every entry carries its own machine and provenance.
    """
    path = DATA / f"bench_{name}.json"
    doc = {**doc, "provenance": provenance()}
    doc.setdefault("machine", machine())
    if merge is not None:
        old = json.loads(path.read_text()) if path.exists() else {}
        entries = {k: {**v, "machine": doc["machine"], "provenance": doc["provenance"]}
                   for k, v in doc[merge].items()}
        doc = {**old, **{k: v for k, v in doc.items() if k not in ("machine", "provenance")},
               merge: {**old.get(merge, {}), **entries}}
    return write_json(path, doc, indent=1, sort_keys=False)


def run_script(main) -> None:
    """Entry of a benchmark script: exit with ``main()``'s status; Ctrl-C and a closed pipe end
    quietly with status 130."""
    try:
        sys.exit(main())
    except (KeyboardInterrupt, BrokenPipeError):
        sys.exit(130)
