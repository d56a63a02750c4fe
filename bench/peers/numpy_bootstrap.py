"""A hand-vectorised NumPy bootstrap filter for AR(1)+noise, the same computation as
`pf-viz bench bootstrap`: diffuse prior N(Y_0, rho^2), systematic resampling at every step,
log-likelihood of Y_1..Y_n given Y_0.

usage: numpy_bootstrap.py DATA.csv N [SEED] [REPEAT]
"""
import sys
import time

import numpy as np

from common import PHI, SIGMA, RHO, best_of, read_y, report


def bootstrap(ys, n, rng):
    log_norm = -0.5 * np.log(2 * np.pi) - np.log(RHO)
    x = ys[0] + RHO * rng.standard_normal(n)
    loglik = 0.0
    w = np.full(n, 1.0 / n)
    for y in ys[1:]:
        # systematic resampling on the previous weights
        u = (rng.random() + np.arange(n)) / n
        a = np.searchsorted(np.cumsum(w), u, side="right")
        np.minimum(a, n - 1, out=a)
        x = PHI * x[a] + SIGMA * rng.standard_normal(n)
        lw = log_norm - 0.5 * ((y - x) / RHO) ** 2
        m = lw.max()
        w = np.exp(lw - m)
        s = w.sum()
        loglik += m + np.log(s / n)
        w /= s
    return loglik


def main():
    ys = np.array(read_y(sys.argv[1]))
    n = int(sys.argv[2])
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    repeat = int(sys.argv[4]) if len(sys.argv) > 4 else 1

    def run():
        rng = np.random.default_rng(seed)
        t0 = time.perf_counter()
        ll = bootstrap(ys, n, rng)
        return time.perf_counter() - t0, ll

    times, ll = best_of(repeat, run)
    report("numpy", n, len(ys) - 1, times, ll)


if __name__ == "__main__":
    main()
