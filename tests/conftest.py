"""Test-suite configuration: a reproducible Hypothesis profile, a headless matplotlib and the
``report`` fixture that records asserted values for the validation report."""

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

_RECORDS: dict = {}


def pytest_report_header(config):
    """The code paths the numbers come from, so that a run on another machine says which it
    took: the CPU numba compiles for (NUMBA_CPU_NAME, or the host's) and the BLAS kernels
    (OPENBLAS_CORETYPE selects them)."""
    import llvmlite.binding
    import numba
    lines = [f"numba {numba.__version__} compiles for "
             f"{numba.config.CPU_NAME or llvmlite.binding.get_host_cpu_name()}"]
    try:
        import numpy.linalg  # noqa: F401 (loads the BLAS libraries to inspect)
        import scipy.linalg  # noqa: F401
        from threadpoolctl import threadpool_info
    except ImportError:
        return lines
    lines += [f"{lib['internal_api']} {lib['version']} kernels {lib.get('architecture')} "
              f"({lib['prefix']})" for lib in threadpool_info() if lib["user_api"] == "blas"]
    return lines


def pytest_collection_modifyitems(items):
    """Mark the tests that record values for the report, so ``-m record`` selects them."""
    for item in items:
        if "report" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.record)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Keep the call phase's report on the item: the ``report`` fixture stores only the records
    of tests that passed."""
    outcome = yield
    if call.when == "call":
        item.validation_passed = outcome.get_result().passed


@pytest.fixture
def report(request):
    """``report.value(key, value, reference=, tol=, kind=, source=) -> value``: the value a
    test asserts, recorded for ``docs/validation.md`` (``tests/validation_report.py``) when
    the environment variable VALIDATION_RECORDS names a directory and the test passes; a
    no-op store otherwise."""
    from validation_report import RECORDS_ENV, Recorder, save_records
    recorder = Recorder(request.node.nodeid, request.node.get_closest_marker("slow") is not None,
                        _RECORDS)
    yield recorder
    if not getattr(request.node, "validation_passed", False):    # a failed test records nothing
        for key in [k for k, r in _RECORDS.items() if r["test"] == request.node.nodeid]:
            del _RECORDS[key]
    directory = os.environ.get(RECORDS_ENV)
    if directory:
        save_records(directory, _RECORDS)


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
