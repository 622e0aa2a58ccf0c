"""The 1,000,000-sample gyro log of the `series` timings in docs/performance.md:
`t,wx,wy,wz`, t every 5 ms with 6 decimals, rates uniform in [-1, 1) rad/s
with 9 decimals (about 49 MB).

usage: python3 bench/gen_gyro.py OUT.csv [SAMPLES]
"""
import sys
import numpy as np


def main(dst, n=1_000_000):
    rng = np.random.default_rng(24)
    w = rng.uniform(-1.0, 1.0, size=(n, 3))
    t = np.arange(n) * 0.005
    with open(dst, "w") as f:
        f.write("t,wx,wy,wz\n")
        for ti, (x, y, z) in zip(t, w):
            f.write(f"{ti:.6f},{x:.9f},{y:.9f},{z:.9f}\n")


if __name__ == "__main__":
    main(sys.argv[1], *(int(a) for a in sys.argv[2:3]))
