"""Do the NumPy and `particles` radar filters estimate the same log-likelihood? Runs each
from seeds 1 … S on one data file and prints, per library, the mean, the standard deviation
over seeds and the standard error of the mean, then the difference of the two means in
standard errors, sqrt(se_numpy² + se_particles²); with `--pfviz PF_VIZ` also pf's
`bench filter --model radar` from the same seeds.

usage: agree_radar.py DATA.csv N S [--pfviz PATH]
"""
import json
import statistics
import subprocess
import sys

import numpy as np

import numpy_radar
import particles_radar
from common import read_radar


def summary(name, lls):
    mean = statistics.fmean(lls)
    sd = statistics.stdev(lls)
    se = sd / len(lls) ** 0.5
    print(json.dumps({"library": name, "seeds": len(lls), "mean": mean, "sd": sd, "se": se,
                      "min": min(lls), "max": max(lls)}))
    return mean, se


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__.strip())
    path, n, s = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    pfviz = sys.argv[sys.argv.index("--pfviz") + 1] if "--pfviz" in sys.argv else None
    ys = read_radar(path)
    runs = {
        "numpy": [numpy_radar.radar_pf(ys, n, np.random.default_rng(seed))
                  for seed in range(1, s + 1)],
        "particles": [],
    }
    for seed in range(1, s + 1):
        pf = particles_radar.radar_smc(ys, n, seed)
        pf.run()
        runs["particles"].append(float(pf.logLt))
    if pfviz:
        runs["pf"] = [
            json.loads(subprocess.run(
                [pfviz, "bench", "filter", "--model", "radar", "--data", path,
                 "--particles", str(n), "--threads", "1", "--seed", str(seed), "--json"],
                check=True, capture_output=True, text=True).stdout)["loglik"]
            for seed in range(1, s + 1)]
    stats = {name: summary(name, lls) for name, lls in runs.items()}
    names = list(stats)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            (ma, sa), (mb, sb) = stats[a], stats[b]
            print(json.dumps({"pair": f"{a} - {b}", "difference": ma - mb,
                              "in_standard_errors": (ma - mb) / (sa ** 2 + sb ** 2) ** 0.5}))


if __name__ == "__main__":
    main()
