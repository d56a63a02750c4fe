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


# Karlsson, Schön & Gustafsson's radar scenario, model (13), with the values of pf-mpf's
# `RadarConfig::default()`: x = [p_x p_y v_x v_y a_x a_y], x_{t+1} = A x_t + w_t,
# w ~ N(0, diag Q); y_t = [range, azimuth] = [hypot(p_x, p_y), atan2(p_y, p_x)] + e_t,
# e ~ N(0, diag R), the azimuth wrapped into (-pi, pi]; x_0 ~ N(X0, diag P0).
RADAR_T = 1.0
RADAR_Q = (1.0, 1.0, 1.0, 1.0, 0.01, 0.01)
RADAR_R = (100.0, 1e-6)
RADAR_X0 = (2000.0, 1500.0, -20.0, 10.0, 0.0, 0.0)
RADAR_P0 = (100.0, 100.0, 25.0, 25.0, 0.1, 0.1)


def radar_a():
    """A of eq. (13a): position += T v + T^2/2 a, velocity += T a."""
    import numpy as np
    a = np.eye(6)
    for i in range(4):
        a[i, i + 2] = RADAR_T
    a[0, 4] = a[1, 5] = RADAR_T ** 2 / 2
    return a


def wrap_angle(a):
    """Into (-pi, pi], as pf_core::geometry::wrap_angle: values already there unchanged."""
    import numpy as np
    a = np.asarray(a, dtype=float)
    r = np.remainder(a, 2 * np.pi)
    r = np.where(r > np.pi, r - 2 * np.pi, r)
    return np.where((a > -np.pi) & (a <= np.pi), a, r)


def simulate_radar(n, seed):
    """n measurements [range, azimuth] of one trajectory of model (13): the true state
    starts at X0 (as pf-mpf's `RadarConfig::truth`, whose first state is x0), and
    y_t measures x_t for t = 0 … n-1."""
    import numpy as np
    rng = np.random.default_rng(seed)
    a = radar_a()
    sq = np.sqrt(RADAR_Q)
    sr = np.sqrt(RADAR_R)
    x = np.array(RADAR_X0)
    ys = []
    for _ in range(n):
        e = rng.standard_normal(2)
        ys.append((float(np.hypot(x[0], x[1]) + sr[0] * e[0]),
                   float(wrap_angle(np.arctan2(x[1], x[0]) + sr[1] * e[1]))))
        x = a @ x + sq * rng.standard_normal(6)
    return ys


def write_radar(path, ys):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["range", "azimuth"])
        for r, az in ys:
            w.writerow([repr(r), repr(az)])


def read_radar(path):
    """The rows of a `range,azimuth` file as an (n, 2) array."""
    import numpy as np
    with open(path, newline="") as f:
        return np.array([[float(row["range"]), float(row["azimuth"])]
                         for row in csv.DictReader(f)])


def report_radar(name, n_particles, steps, times, loglik):
    """One JSON line with the keys of `pf-viz bench filter --json` (`model` = "radar"), plus
    `library`; `seconds` is the fastest run, `seconds_median` the median as in `report`."""
    fastest = min(times)
    print(json.dumps({
        "model": "radar",
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
