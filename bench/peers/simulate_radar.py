"""Write a radar data set from model (13) (pf-mpf's RadarConfig defaults): header
`range,azimuth`, one row per time step t = 0 … STEPS-1.

usage: simulate_radar.py OUT.csv STEPS SEED
"""
import sys

from common import simulate_radar, write_radar

if len(sys.argv) != 4:
    sys.exit(__doc__.strip())
write_radar(sys.argv[1], simulate_radar(int(sys.argv[2]), int(sys.argv[3])))
