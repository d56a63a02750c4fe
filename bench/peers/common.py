"""Shared by the peer benchmarks: the AR(1)+noise data set and the JSON report."""
import csv
import json
import statistics

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


def best_of(repeat, run):
    """`run()` -> (seconds, loglik), called `repeat` times; each call seeds its own generator
    the same way, so every run gives the same estimate, and the fastest is the least
    disturbed by other work on the machine (as `pf-viz bench bootstrap --repeat`). Returns
    the times and the estimate."""
    times, loglik = [], None
    for _ in range(max(1, repeat)):
        seconds, loglik = run()
        times.append(seconds)
    return times, loglik


def report(name, n_particles, steps, times, loglik):
    """One JSON line with the keys of `pf-viz bench bootstrap --json`: `seconds` is the
    fastest of the runs, `seconds_median` their median (the higher middle one for an even
    count, as `pf-viz` takes it)."""
    fastest = min(times)
    print(json.dumps({
        "library": name,
        "particles": n_particles,
        "steps": steps,
        "threads": 1,
        "seconds": fastest,
        "ns_per_particle_step": fastest * 1e9 / (n_particles * steps),
        "loglik": loglik,
        "repeat": len(times),
        "seconds_median": statistics.median_high(times),
    }))
