"""Helpers shared by the CLI tests (imported by test modules; pytest puts tests/ on sys.path)."""

import json


def _reject_constant(name):
    raise ValueError(f"not strict JSON: {name}")


def strict_json(text: str) -> dict:
    """Parse stdout as exactly one JSON object (no NaN/Infinity, nothing before or after)."""
    obj = json.loads(text, parse_constant=_reject_constant)
    assert isinstance(obj, dict)
    return obj
