"""The radar standard PF of model (13) (all six states in the particle filter, PPPPPP) in
Nicolas Chopin's `particles` library: `ssm.Bootstrap` (the bootstrap proposal), `SMC` with
`resampling="systematic"` and `ESSrmin=1` (resampling at every step).

`particles` draws X_0 from PX0 and weighs it by the first observation, as pf-mpf's filter and
`pf-viz bench filter --model radar` do, so the data are every row and `logLt` estimates
log p(y_0 … y_{n-1}).

usage: particles_radar.py DATA.csv N [SEED] [REPEAT]
"""
import sys
import time

import numpy as np
import particles
from particles import distributions as dists
from particles import state_space_models as ssm

from common import (RADAR_P0, RADAR_Q, RADAR_R, RADAR_X0, best_of, radar_a, read_radar,
                    report_radar, wrap_angle)


class Radar(ssm.StateSpaceModel):
    """Model (13): x_{t+1} = A x_t + w_t, y_t = [range, azimuth](x_t) + e_t.

    `ys` (the data) lets PY wrap the azimuth residual as pf does: the azimuth's location is
    atan2(p_y, p_x) shifted by the multiple of 2 pi that brings y_t - location into
    (-pi, pi] (no shift when it is there already)."""

    default_params = {"ys": None}
    A_T = radar_a().T
    COV_Q = np.diag(RADAR_Q)
    COV_P0 = np.diag(RADAR_P0)
    SD_R = np.sqrt(RADAR_R)

    def PX0(self):
        return dists.MvNormal(loc=np.array(RADAR_X0), cov=self.COV_P0)

    def PX(self, t, xp):
        return dists.MvNormal(loc=xp @ self.A_T, cov=self.COV_Q)

    def PY(self, t, xp, x):
        px, py = x[:, 0], x[:, 1]
        azimuth = np.arctan2(py, px)
        d = self.ys[t, 1] - azimuth
        return dists.IndepProd(
            dists.Normal(loc=np.hypot(px, py), scale=self.SD_R[0]),
            dists.Normal(loc=azimuth + (d - wrap_angle(d)), scale=self.SD_R[1]),
        )


def radar_smc(ys, n, seed):
    """The filter on `ys`, seeded with `seed` (NumPy's global generator, which `particles`
    draws from), not yet run."""
    np.random.seed(seed)
    fk = ssm.Bootstrap(ssm=Radar(ys=ys), data=ys)
    pf = particles.SMC(fk=fk, N=n, resampling="systematic", ESSrmin=1.0,
                       collect=None, store_history=False, verbose=False)
    return pf


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__.strip())
    ys = read_radar(sys.argv[1])
    n = int(sys.argv[2])
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    repeat = int(sys.argv[4]) if len(sys.argv) > 4 else 1

    def run():
        pf = radar_smc(ys, n, seed)
        t0 = time.perf_counter()
        pf.run()
        return time.perf_counter() - t0, float(pf.logLt)

    times, ll = best_of(repeat, run)
    report_radar("particles", n, len(ys), times, ll)


if __name__ == "__main__":
    main()
