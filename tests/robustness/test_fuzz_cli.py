"""Fuzzing the command line against its contract (lubrication/cli_contract.py).

Hypothesis draws command lines for every command, with option values that include NaN, ±inf,
subnormals, huge numbers, zero, negatives, strings and empty strings, missing and conflicting
options. Every example must end, within a per-example time limit, in one of:

* exit 0 with finite numbers (``--json``: strict JSON; table: no ``nan``/``inf``);
* exit 2 with exactly one line on stderr, nothing on stdout;
* exit 1 with a solver message and, with ``--json``, no physical numbers of the failed solve;

never an exception (a traceback for the user) and never a hang. Solver commands run with
``--max-time`` so that a valid drawn case is bounded too. The whole module is budgeted at about
a minute of the default suite.
"""

from __future__ import annotations

import contextlib
import io
import json
import signal

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from probe_campaign import MODEL_NAMES, NON_FINITE, PHYSICAL_KEYS  # the same contract checks

from correlations.cli import main

TIME_LIMIT_S = 20          # per example; a solver command also gets --max-time (below)


class Hang(BaseException):
    """Raised by the alarm: the example exceeded its time limit."""


def _alarm(signum, frame):
    raise Hang()


# Nasty values: special strings, and numbers written as a user might.
SPECIAL = st.sampled_from(["nan", "NaN", "inf", "-inf", "Infinity", "1e308", "1e309", "-1e308",
                           "1e-320", "5e-324", "0", "-0", "-1", "", "abc", "1,5", "0x10", "1e",
                           "  2 ", "1_000"])
NUMBERS = st.floats(allow_nan=True, allow_infinity=True, width=64).map(repr)
VALUES = st.one_of(SPECIAL, NUMBERS, st.integers(-10**12, 10**12).map(str))


def _typical(*values):
    """Typical valid values, drawn three times as often as the nasty ones so that the valid
    paths (and their outputs) are exercised too."""
    typical = st.sampled_from([str(v) for v in values])
    return st.sampled_from((typical, typical, typical, VALUES)).flatmap(lambda s: s)


# command -> (fixed argv prefix, {option: strategy of its value}); flags are drawn separately.
CHEAP = {
    "geometry": (["geometry"], {"--nu": _typical(0.6, 0.9, 1.0), "--lam": _typical(0.5, 1.2, 1.9),
                                "--volume-fl": _typical(90), "--area-um2": _typical(135),
                                "--diameter-um": _typical(4, 8)}),
    "estimate": (["estimate"], {"--volume-fl": _typical(90, 60), "--area-um2": _typical(135),
                                "--diameter-um": _typical(3, 4, 6),
                                "--velocity-mm-s": _typical(1, 0.1),
                                "--plasma-viscosity-mpas": _typical(1.2),
                                "--bending-modulus-j": _typical(2e-19),
                                "--hematocrit": _typical(0.3, 0.45),
                                "--hematocrit-kind": st.sampled_from(["tube", "discharge", "x"])}),
    "estimate-nu": (["estimate"], {"--nu": _typical(0.6, 0.9, 0.98), "--lam": _typical(0.3, 1.0),
                                   "--ca-b": _typical(5, 50), "--hematocrit": _typical(0.3)}),
    "viscosity": (["viscosity"], {"--diameter-um": _typical(2, 4, 6, 100),
                                  "--hematocrit": _typical(0.3, 0.45),
                                  "--law": st.sampled_from(["pries1992", "pries1994", "pries2005",
                                                            "single-file", "x"]),
                                  "--hematocrit-kind": st.sampled_from(["tube", "discharge"]),
                                  "--constants": st.sampled_from(["pries1990", "pries1992"])}),
    "fahraeus": (["fahraeus"], {"--diameter-um": _typical(2, 2.8, 10),
                                "--discharge-hematocrit": _typical(0.45),
                                "--tube-hematocrit": _typical(0.3)}),
}
SOLVERS = {
    "lubrication": (["lubrication", "--max-time", "2"],
                    {"--nu": _typical(0.9), "--lam-ratio": _typical(0.99), "--lam": _typical(1.0),
                     "--ca-b": _typical(50, "inf"), "--from": _typical(0.95),
                     "--to": _typical(0.99), "--points": _typical(2, 3)}),
    "bem-sphere": (["bem", "sphere"], {"--lam": _typical(0.3, 0.5), "--tol": _typical(1e-6),
                                       "--panels": _typical(4, 8)}),
    "bem-drop": (["bem", "drop", "--max-time", "2"],
                 {"--lam": _typical(0.3), "--ca": _typical(0.1), "--tol": _typical(1e-3),
                  "--modes": _typical(8)}),
    "bem-vesicle": (["bem", "vesicle", "--max-time", "2"],
                    {"--nu": _typical(0.98), "--lam": _typical(0.3), "--ca-b": _typical(50),
                     "--tol": _typical(1e-2), "--residual-tol": _typical(1e-2),
                     "--modes": _typical(8), "--max-modes": _typical(12)}),
}


@st.composite
def command_lines(draw, table):
    name = draw(st.sampled_from(sorted(table)))
    prefix, options = table[name]
    chosen = draw(st.lists(st.sampled_from(sorted(options)), unique=True,
                           max_size=len(options)))
    argv = list(prefix)
    for opt in chosen:
        argv += [opt, draw(options[opt])]
    if draw(st.booleans()):
        argv.append("--json")
    if name == "lubrication" and draw(st.booleans()):
        argv.append("--sweep")
    return argv


def run_cli(argv):
    """``main(argv)`` in-process with a time limit: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIME_LIMIT_S)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:
                code = exc.code
    except Hang:
        pytest.fail(f"hang: {argv} took more than {TIME_LIMIT_S} s")
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return code, out.getvalue(), err.getvalue()


def assert_contract(argv, code, out, err):
    """The contract of lubrication/cli_contract.py for one run."""
    assert code in (0, 1, 2), f"{argv}: exit {code!r}\n{err}"
    assert "Traceback" not in err, f"{argv}:\n{err}"
    if code == 2:
        lines = err.strip("\n").splitlines()
        assert out == "" and len(lines) == 1 and "error" in lines[0], f"{argv}:\n{out}\n{err}"
        return
    if "--help" in argv:
        return
    if "--json" in argv:
        obj = json.loads(out, parse_constant=lambda c: pytest.fail(f"{argv}: {c} in JSON"))
        assert isinstance(obj, dict)
        if code == 1:
            given = {k: obj[k] for k in PHYSICAL_KEYS if obj.get(k) is not None}
            assert not given, f"{argv}: numbers from a failed solve {given}"
    elif code == 0:
        assert not NON_FINITE.search(MODEL_NAMES.sub("", out)), \
            f"{argv}: non-finite number printed\n{out}"
    if code == 1:
        assert err.strip(), f"{argv}: exit 1 without a message"


FUZZ = settings(max_examples=300, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


@FUZZ
@given(argv=command_lines(CHEAP))
def test_cheap_commands_keep_the_contract(argv):
    assert_contract(argv, *run_cli(argv))


@settings(FUZZ, max_examples=80)
@given(argv=command_lines(SOLVERS))
def test_solver_commands_keep_the_contract(argv):
    assert_contract(argv, *run_cli(argv))


@settings(FUZZ, max_examples=100)
@given(argv=st.lists(st.one_of(st.sampled_from(
    ["geometry", "estimate", "viscosity", "fahraeus", "lubrication", "bem", "sphere", "--nu",
     "--lam", "--json", "--plot", "--out", "--solver", "bem", "--help", "-h", "0.5"]),
    st.text(max_size=8)), max_size=6))
def test_arbitrary_words_keep_the_contract(argv):
    """Random words: missing and conflicting options, unknown commands, stray values."""
    if "--help" in argv or "-h" in argv:
        argv = [a for a in argv if a not in ("--help", "-h")]
    assert_contract(argv, *run_cli(argv))
