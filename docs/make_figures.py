"""Regenerate the figures of docs/ (run: .venv/bin/python docs/make_figures.py)."""

from pathlib import Path

from matplotlib.figure import Figure

from correlations.estimate import estimate
from correlations.plotting import (plot_estimate, plot_relative_viscosity,
                                   plot_single_file_viscosity)
from lubrication.plotting import plot_dp_plus_asymptotics, plot_speed_asymptotics

OUT = Path(__file__).with_name("figures")


def main() -> None:
    OUT.mkdir(exist_ok=True)
    fig = Figure(figsize=(10, 4))
    ax = fig.subplots(1, 2)
    plot_speed_asymptotics(ax=ax[0])
    plot_dp_plus_asymptotics(ax=ax[1])
    fig.savefig(OUT / "asymptotics.png", dpi=110, bbox_inches="tight")

    ax = plot_relative_viscosity(hematocrits=(0.2, 0.45))
    ax.set_yscale("log")
    ax.figure.savefig(OUT / "viscosity_laws.png", dpi=110, bbox_inches="tight")

    # the asymptotic laws drawn there are the vesicle's: the vesicle model of the cell
    plot_estimate(estimate(diameter_um=3.0, membrane="vesicle")).figure.savefig(
        OUT / "estimate_rbc_3um.png", dpi=110, bbox_inches="tight")

    plot_single_file_viscosity(0.3).figure.savefig(OUT / "single_file_velocities.png", dpi=110,
                                                   bbox_inches="tight")


if __name__ == "__main__":
    main()
