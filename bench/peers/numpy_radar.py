"""A hand-vectorised NumPy standard PF for the radar model (13), every one of the six states
in the particle filter (the paper's PPPPPP), as `pf-viz bench filter --model radar`: the
bootstrap proposal, systematic resampling at every step, the initial law N(X0, diag P0)
weighed by y_0, so the log-likelihood estimates log p(y_0 … y_{n-1}).

The particles are a 6×N array, one row per state (structure of arrays); every operation
works on whole rows, in place where NumPy allows it.

usage: numpy_radar.py DATA.csv N [SEED] [REPEAT]
"""
import sys
import time

import numpy as np

from common import (RADAR_P0, RADAR_Q, RADAR_R, RADAR_T, RADAR_X0, best_of, read_radar,
                    report_radar)


def radar_pf(ys, n, rng):
    """Run the filter on `ys` ((steps, 2): range, azimuth); return the log-likelihood."""
    t, half_t2 = RADAR_T, RADAR_T ** 2 / 2
    sq = np.sqrt(RADAR_Q)[:, None]
    inv_r0, inv_r1 = 1.0 / RADAR_R[0], 1.0 / RADAR_R[1]
    # ½ log det(2π R), R diagonal 2×2
    half_log_det = np.log(2 * np.pi) + 0.5 * np.log(RADAR_R[0] * RADAR_R[1])
    index = np.arange(n)
    x = np.empty((6, n))
    rng.standard_normal(out=x)
    x *= np.sqrt(RADAR_P0)[:, None]
    x += np.asarray(RADAR_X0)[:, None]
    xa = np.empty_like(x)
    scratch = np.empty((4, n))
    e_r = np.empty(n)
    e_a = np.empty(n)
    w = np.empty(n)
    loglik = 0.0
    for k, (y_r, y_a) in enumerate(ys):
        if k > 0:
            # Systematic resampling on the weights of step k-1: with C the cumulative
            # weights scaled to n and U uniform, particle i has ceil(C_i - U) - ceil(C_{i-1}
            # - U) offspring, the ancestors of the points (j + U)/n, j = 0 … n-1.
            c = np.cumsum(w)
            c *= n / c[-1]
            c[-1] = n
            c -= rng.random()
            np.ceil(c, out=c)
            counts = np.diff(c, prepend=0.0).astype(np.intp)
            np.take(x, np.repeat(index, counts), axis=1, out=xa)
            # x_k = A x_{k-1} + sqrt(Q) z, the A of eq. (13a) written out
            rng.standard_normal(out=x)
            x *= sq
            x += xa
            np.multiply(xa[2:6], t, out=scratch)
            x[0:4] += scratch
            np.multiply(xa[4:6], half_t2, out=scratch[0:2])
            x[0:2] += scratch[0:2]
        px, py = x[0], x[1]
        # range residual y_r - sqrt(p_x² + p_y²)
        np.multiply(px, px, out=e_r)
        np.multiply(py, py, out=w)
        e_r += w
        np.sqrt(e_r, out=e_r)
        np.subtract(y_r, e_r, out=e_r)
        # azimuth residual y_a - atan2(p_y, p_x), wrapped into (-pi, pi] if it leaves it
        np.arctan2(py, px, out=e_a)
        np.subtract(y_a, e_a, out=e_a)
        if not (e_a.min() > -np.pi and e_a.max() <= np.pi):
            r = np.remainder(e_a, 2 * np.pi)
            r[r > np.pi] -= 2 * np.pi
            np.copyto(e_a, r, where=(e_a <= -np.pi) | (e_a > np.pi))
        # log weights -½ (e_r² / R_0 + e_a² / R_1) (less ½ log det(2π R), added below)
        np.multiply(e_r, e_r, out=e_r)
        e_r *= -0.5 * inv_r0
        np.multiply(e_a, e_a, out=w)
        w *= -0.5 * inv_r1
        w += e_r
        m = w.max()
        w -= m
        np.exp(w, out=w)
        # log of the mean weight (the previous weights are uniform after resampling)
        loglik += m - half_log_det + np.log(w.sum() / n)
    return loglik


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__.strip())
    ys = read_radar(sys.argv[1])
    n = int(sys.argv[2])
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    repeat = int(sys.argv[4]) if len(sys.argv) > 4 else 1

    def run():
        rng = np.random.default_rng(seed)
        t0 = time.perf_counter()
        ll = radar_pf(ys, n, rng)
        return time.perf_counter() - t0, ll

    times, ll = best_of(repeat, run)
    report_radar("numpy", n, len(ys), times, ll)


if __name__ == "__main__":
    main()
