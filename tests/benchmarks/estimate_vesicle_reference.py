"""The vesicle estimate as it was before red cells were added: reference answers.

``estimate(..., membrane="vesicle")`` must stay bit for bit the estimate of the revision before
the red-cell membrane (tests/correlations/test_estimate_red_cell.py). This script writes the
reference, ``to_dict()`` without the provenance for a few cases, with the SHA-256 of the
shipped vesicle map the answers depend on::

    python tests/benchmarks/estimate_vesicle_reference.py            # compare, print a table
    python tests/benchmarks/estimate_vesicle_reference.py --write    # write the reference

The stored file was first written at the revision before red cells (where ``estimate()`` had
no ``membrane``); write it again only when the vesicle estimate is meant to change (e.g. a new
shipped vesicle map).
"""

from __future__ import annotations

import hashlib
import inspect
import json
import sys
from pathlib import Path

from correlations.estimate import estimate
from correlations.solution_map import DEFAULT_MAP

REFERENCE = Path(__file__).parents[1] / "correlations" / "data" / "estimate_vesicle_reference.json"

#: keyword arguments of estimate() of each case (the vesicle's, without ``membrane``)
CASES = {"default": {}, "d3": {"diameter_um": 3.0}, "nomap": {"solution_map": False},
         "hct": {"hematocrit": 0.3}, "slow": {"velocity_mm_s": 0.1},
         "extrap": {"diameter_um": 6.0, "extrapolate": True, "hematocrit": 0.2,
                    "hematocrit_kind": "discharge"},
         "d5": {"diameter_um": 5.0, "velocity_mm_s": 3.0}}


def answers() -> dict:
    """``to_dict()`` of every case without the provenance, through JSON (as stored)."""
    vesicle = ({"membrane": "vesicle"} if "membrane" in inspect.signature(estimate).parameters
               else {})
    out = {}
    for name, kw in CASES.items():
        d = estimate(**kw, **vesicle).to_dict()
        d.pop("provenance")
        out[name] = json.loads(json.dumps(d))
    return out


def map_sha256() -> str | None:
    return hashlib.sha256(DEFAULT_MAP.read_bytes()).hexdigest() if DEFAULT_MAP.exists() else None


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    got = answers()
    if "--write" in argv:
        REFERENCE.write_text(json.dumps({"made_by": "python tests/benchmarks/"
                                         "estimate_vesicle_reference.py --write",
                                         "map_sha256": map_sha256(), "cases": CASES,
                                         "answers": got}, indent=1, sort_keys=True) + "\n")
        print(f"wrote {REFERENCE}")
        return 0
    ref = json.loads(REFERENCE.read_text())
    print(f"{'case':8s} {'same':5s} V/U")
    same = True
    for name in CASES:
        ok = got[name] == ref["answers"][name]
        same &= ok
        print(f"{name:8s} {str(ok):5s} {got[name]['V_over_U']}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
