"""Reference: the same job as `mmbm series` (thesis camera, 8x6 midpoint grid,
rotation-only MMBM per gyro sample) done the straightforward way with pandas
and numpy, for the side-by-side timing in docs/performance.md.

usage: python3 bench/series_pandas.py GYRO.csv OUT.csv
"""
import sys
import numpy as np
import pandas as pd

F, P, W, H, NU, NV = 4.2548, 0.00465, 640, 480, 8, 6


def main(src, dst):
    df = pd.read_csv(src, comment="#")
    wx, wy, wz = (df[c].to_numpy()[:, None] for c in ("wx", "wy", "wz"))
    cu = (np.arange(NU) + 0.5) * (W / NU) - W / 2
    cv = (np.arange(NV) + 0.5) * (H / NV) - H / 2
    u, v = np.meshgrid(cu * P, cv * P)
    u, v = u.ravel()[None, :], v.ravel()[None, :]
    du = wz * v - wy * F - (wy / F) * u**2 + (wx / F) * u * v
    dv = -wz * u + wx * F - (wy / F) * u * v + (wx / F) * v**2
    mm = np.sqrt(du**2 + dv**2).mean(axis=1)
    pd.DataFrame({"t": df["t"], "mmbm_mm_s": mm, "mmbm_px_s": mm / P}).to_csv(dst, index=False)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
