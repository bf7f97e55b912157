"""The cost of a force from Python against the same force built in.

A constant body force on N free-draining spheres, once as the scenario's `system.body_force`
and once as a Python callable (`Engine.add_force`, evaluated before every step), on one thread;
interleaved rounds, medians printed. Usage: python examples/python/custom_force_cost.py [N ...]
"""

import statistics
import sys
import time

import numpy as np

import colloidsim


def per_step(engine: colloidsim.Engine, steps: int) -> float:
    t = time.perf_counter()
    engine.step(steps, threads=1)
    return (time.perf_counter() - t) / steps


def main(sizes):
    print(f"{'N':>7} {'built-in us/step':>17} {'Python us/step':>15} {'ratio':>6}")
    for n in sizes:
        keys = dict(method="bd", particles=n, box_length=(n / 0.125) ** (1 / 3), dt=1e-4, seed=1)
        force = np.tile([1.0, 0.0, 0.0], (n, 1))
        built, python = [], []
        for _ in range(5):
            a = colloidsim.BrownianDynamics(**keys, body_force=[1.0, 0.0, 0.0])
            a.step(20, threads=1)
            built.append(per_step(a, 300))
            b = colloidsim.BrownianDynamics(**keys)
            b.add_force(lambda e: force)
            b.step(20, threads=1)
            python.append(per_step(b, 300))
        tb, tp = statistics.median(built), statistics.median(python)
        print(f"{n:>7} {tb * 1e6:>17.1f} {tp * 1e6:>15.1f} {tp / tb:>6.1f}")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [100, 1000, 10000])
