"""Shared by the peer benchmarks: the AR(1)+noise data set and the JSON report."""
import csv
import json

PHI, SIGMA, RHO = 0.98, 0.2, 1.0


def read_y(path):
    with open(path, newline="") as f:
        return [float(row["y"]) for row in csv.DictReader(f)]


def simulate(n, seed):
    import numpy as np
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, SIGMA / (1 - PHI ** 2) ** 0.5)
    ys = []
    for _ in range(n + 1):
        ys.append(x + RHO * rng.normal())
        x = PHI * x + SIGMA * rng.normal()
    return ys


def write_y(path, ys):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["y"])
        for y in ys:
            w.writerow([repr(y)])


def report(name, n_particles, steps, seconds, loglik):
    print(json.dumps({
        "library": name,
        "particles": n_particles,
        "steps": steps,
        "threads": 1,
        "seconds": seconds,
        "ns_per_particle_step": seconds * 1e9 / (n_particles * steps),
        "loglik": loglik,
    }))
