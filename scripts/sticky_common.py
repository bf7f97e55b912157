"""What the scripts of the hard-rods paper's Fig. 6 share (sticky rods, sigma = rho, U0 = 6 kT,
p = 3, L = 100): reading colloidsim's CSV tables, the exact eps -> 0 theory's profile, and the
peak deviation every table quotes (three bins around the theory's maximum)."""
import csv
import math
import os
import subprocess

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = os.path.join(HERE, "examples", "bcd", "sticky-rods.toml")
COLLOIDSIM = os.path.join(HERE, "target", "release", "colloidsim")
STICKY_MC = os.path.join(HERE, "target", "release", "examples", "sticky_profile_mc")
L, U0 = 100, 6


def rods(sigma):
    """Rods on the ring of length L at mean density sigma."""
    return round(sigma * L)


def table(path):
    """A CSV table as {column: [values]}."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def theory(binary, folder, sigma, gamma, bins=50):
    """The eps -> 0 theory's profile on `bins` bins (`colloidsim theory`, run once into
    `folder`)."""
    path = os.path.join(folder, "density.csv")
    if not os.path.exists(path):
        subprocess.run([binary, "theory", SCENARIO, "--out", folder, "--force",
                        "--set", f"system.diameter={sigma}",
                        "--set", f"system.particles={rods(sigma)}",
                        "--set", f"interaction.sticky.gamma={gamma}",
                        "--set", f"observe.density.bins={bins}"],
                       check=True, stdout=subprocess.DEVNULL)
    return table(path)["rho"]


def peak_window(th):
    """The three bins around the theory's maximum and the theory's sum over them."""
    top = max(range(len(th)), key=lambda i: th[i])
    window = [(top + j) % len(th) for j in (-1, 0, 1)]
    return window, sum(th[i] for i in window)


def peak(rho, th, err=None):
    """The relative deviation of a profile's peak from the theory's (three bins), and its error
    from per-bin errors `err` when given."""
    window, pt = peak_window(th)
    dev = sum(rho[i] for i in window) / pt - 1.0
    if err is None:
        return dev
    return dev, math.sqrt(sum(err[i] ** 2 for i in window)) / pt
