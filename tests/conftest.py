"""Test-suite configuration: a reproducible Hypothesis profile and a headless matplotlib."""

import os

import matplotlib
import pytest
from hypothesis import HealthCheck, settings

matplotlib.use("Agg")

# deadline=None: numba compiles on first call; derandomize: CI runs are reproducible.
settings.register_profile("ci", deadline=None, derandomize=True, max_examples=60,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", deadline=None, max_examples=1000)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture
def cli(capsys):
    """Run the vesicle-tube command line in-process: ``cli(*argv) -> (exit code, stdout,
    stderr)`` (SystemExit, e.g. from argparse, gives its code)."""
    from correlations.cli import main

    def run(*argv):
        try:
            code = main(list(argv))
        except SystemExit as exc:
            code = exc.code
        out, err = capsys.readouterr()
        return code, out, err
    return run


@pytest.fixture
def cli_usage_error(cli):
    """``cli_usage_error(*argv) -> line``: asserts the CLI contract for invalid input (exit 2,
    nothing on stdout, one "error" line on stderr, no traceback) and returns that line."""
    def run(*argv):
        code, out, err = cli(*argv)
        assert code == 2
        assert out == ""
        lines = err.strip("\n").splitlines()
        assert len(lines) == 1, err
        assert "Traceback" not in err and "error" in lines[0]
        return lines[0]
    return run
