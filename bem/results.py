"""Result of a BEM computation: a frozen dataclass with inputs, outputs, accuracy and provenance.

Saved as JSON through a temporary file in the target directory and :func:`os.replace`, so an
interrupted run never leaves a half-written file.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import platform
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["SphereResult", "provenance"]


def provenance() -> dict:
    """Versions of Python, the package and its numerical dependencies."""
    from importlib import metadata

    out = {"python": platform.python_version()}
    for name in ("vesicle-tube", "numpy", "scipy", "numba"):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:       # pragma: no cover - not installed
            out[name] = "unknown"
    return out


@dataclass(frozen=True)
class SphereResult:
    """Rigid sphere of radius a = lam R on the axis of a tube (BEM).

    Scalings: U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity.

    Attributes
    ----------
    lam : float
        a/R [-].
    V_over_U : float
        Velocity of the force-free sphere in Poiseuille flow over U [-].
    dp_plus_R, dp_plus_R0 : float
        Extra pressure drop at fixed flow rate, Δp⁺R/(ηU) and Δp⁺a/(ηU) [-].
    drag_K : float
        Drag of the sphere translating at V through fluid at rest far away (zero net flux),
        K = F/(6π η a V) [-].
    dp_translating_R : float
        Pressure rise Δp R/(ηV) across the translating sphere (upstream minus downstream;
        negative: the sphere pushes the fluid) [-].
    *_err : float
        Error estimates: absolute difference between the reported (fine) solution and the
        coarse one of the refinement pair (conservative for the observed high order).
    converged : bool
        Whether every relative error estimate met ``tol``.
    panels, panels_coarse : dict
        Panel counts (body, wall, inlet) and Gauss order of the fine and coarse meshes.
    residual : float
        max |A z - b| / max |b| of the fine linear system.
    null_multiplier : float
        Multiplier of the null-vector bordering column (0 for the exact solution).
    """

    lam: float
    V_over_U: float
    dp_plus_R: float
    dp_plus_R0: float
    drag_K: float
    dp_translating_R: float
    V_over_U_err: float
    dp_plus_R_err: float
    drag_K_err: float
    converged: bool
    tol: float
    panels: dict
    panels_coarse: dict
    half_length: float
    residual: float
    null_multiplier: float
    timings: dict
    provenance: dict = field(default_factory=provenance)
    message: str = ""

    def to_dict(self) -> dict:
        """Plain dict of JSON-compatible values (non-finite floats become None)."""
        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if hasattr(v, "item"):
                return clean(v.item())
            return v
        return {k: clean(v) for k, v in dataclasses.asdict(self).items()}

    def save(self, directory, name: str | None = None) -> Path:
        """Write ``<directory>/<name>.json`` atomically; returns the path."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        name = name or f"bem_sphere_lam{self.lam:.6g}"
        path = directory / f"{name}.json"
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "w") as fh:
                json.dump(self.to_dict(), fh, indent=2, sort_keys=True)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
        return path
