"""Store the fixed self-panel rule's log rule, bem/_log_rule_table.py (a second).

:func:`bem.quadrature.fit_log_rule` at SELF_BASIS, written as exact float literals, so that the
BEM integrates self panels with the same nodes on every CPU (the fit's node selection follows
the rounding of numpy's log and LAPACK). Rerun only when SELF_BASIS or the fit changes; the
table's moments are tested against their closed forms (tests/bem/test_quadrature_self_rule.py).

Run from the repository root: ``.venv/bin/python tests/bem/data/make_log_rule_table.py``
"""

from __future__ import annotations

import os
from pathlib import Path

from bem.quadrature import SELF_BASIS, fit_log_rule

TABLE = Path(__file__).resolve().parents[3] / "bem" / "_log_rule_table.py"


def main() -> None:
    u, w = fit_log_rule(SELF_BASIS)
    lines = [f'"""Nodes and weights of the log rule on [0, 1] for SELF_BASIS = {SELF_BASIS}',
             "(bem.quadrature.log_rule), written by tests/bem/data/make_log_rule_table.py from",
             'bem.quadrature.fit_log_rule: do not edit."""', "",
             "NODES = ("] + [f"    {float(x)!r}," for x in u] + [")", "", "WEIGHTS = ("] + \
        [f"    {float(x)!r}," for x in w] + [")", ""]
    tmp = TABLE.with_suffix(".tmp")
    tmp.write_text("\n".join(lines))
    os.replace(tmp, TABLE)
    print(f"{TABLE}: {u.size} nodes, smallest {u.min():.3g}")


if __name__ == "__main__":
    main()
