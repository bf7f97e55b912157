"""Hard rods in a cosine potential (hard-rods paper Fig. 3): BCD from Python beside the exact
theory, plotted with matplotlib.

    pip install ./python matplotlib
    python examples/python/bcd_beside_theory.py [OUT_DIR]

Runs examples/bcd/hard-rods-cosine.toml for a shorter sampled time (about a second), computes
the exact equilibrium on the same bins, and writes OUT_DIR/density.png (default: a new
temporary folder). The script prints where the picture is and how far the two curves are apart.
"""

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import colloidsim

SCENARIO = Path(__file__).resolve().parents[1] / "bcd" / "hard-rods-cosine.toml"


def main(out: Path) -> float:
    out.mkdir(parents=True, exist_ok=True)
    # A shorter sampled time than the example file's 100: the same physics, a noisier histogram.
    run = colloidsim.run(SCENARIO, out=out / "run", overrides={"run.time": 40.0}, force=True)
    theory = colloidsim.theory(SCENARIO, out=out / "theory", force=True)
    x, rho = run.density.x, run.density.rho
    exact = theory.density.rho
    # Statistical error of a bin: Poisson counts over the sampled configurations.
    n, length = run.summary["parameters"]["system"]["particles"], run.summary["parameters"]["system"]["length"]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax.plot(x, exact, color="k", lw=1.5, label="exact theory (Percus)")
    ax.plot(x, rho, "o", ms=3, color="tab:blue", label=f"BCD, N = {n}, L = {length:g}")
    ax.set_xlabel(r"$x / \lambda$")
    ax.set_ylabel(r"$\rho(x)$")
    ax.set_title(r"Hard rods, $\sigma = 0.5$, $U_0 = 6\,kT$, mean density 0.5")
    ax.legend()
    fig.tight_layout()
    picture = out / "density.png"
    fig.savefig(picture, dpi=120)
    rel = float(np.max(np.abs(rho - exact)) / np.max(exact))
    print(f"{picture}: largest difference {100 * rel:.1f} % of the peak density")
    return rel


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="colloidsim-")))
