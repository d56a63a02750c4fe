"""Write the shared data set: usage: simulate.py OUT.csv STEPS [SEED]"""
import sys

from common import simulate, write_y

write_y(sys.argv[1], simulate(int(sys.argv[2]), int(sys.argv[3]) if len(sys.argv) > 3 else 1))
