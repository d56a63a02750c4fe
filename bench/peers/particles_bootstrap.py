"""The same AR(1)+noise bootstrap filter in Nicolas Chopin's `particles` library.

`particles` weighs its first particles by the first observation, so the diffuse prior is
expressed through X_1 itself: X_0 ~ N(Y_0, rho^2) gives X_1 ~ N(phi Y_0, phi^2 rho^2 +
sigma^2), and the filter then runs on Y_1..Y_n. Its log-likelihood is log p(Y_1..Y_n | Y_0),
the quantity `pf-viz bench bootstrap` reports.

usage: particles_bootstrap.py DATA.csv N [SEED] [REPEAT]
"""
import sys
import time

import numpy as np
import particles
from particles import distributions as dists
from particles import state_space_models as ssm

from common import PHI, SIGMA, RHO, best_of, read_y, report


class DiffuseAR1(ssm.StateSpaceModel):
    default_params = {"y0": 0.0}

    def PX0(self):
        return dists.Normal(loc=PHI * self.y0, scale=np.sqrt(PHI ** 2 * RHO ** 2 + SIGMA ** 2))

    def PX(self, t, xp):
        return dists.Normal(loc=PHI * xp, scale=SIGMA)

    def PY(self, t, xp, x):
        return dists.Normal(loc=x, scale=RHO)


def main():
    ys = read_y(sys.argv[1])
    n = int(sys.argv[2])
    seed = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    repeat = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    model = DiffuseAR1(y0=ys[0])

    def run():
        np.random.seed(seed)
        fk = ssm.Bootstrap(ssm=model, data=np.array(ys[1:]))
        pf = particles.SMC(fk=fk, N=n, resampling="systematic", ESSrmin=1.0,
                           collect=None, store_history=False, verbose=False)
        t0 = time.perf_counter()
        pf.run()
        return time.perf_counter() - t0, float(pf.logLt)

    times, ll = best_of(repeat, run)
    report("particles", n, len(ys) - 1, times, ll)


if __name__ == "__main__":
    main()
