"""Times ``mmbm.augment`` against the usual alternatives on the same 640 x 480
float32 (linear) images with about 20 px of blur (a constant yaw over 30 ms,
reference pose mid-exposure), and measures each one's error against the
exact time integral (``integrator="exact"``: warp samples 1/32 px apart),
in 8-bit levels (|difference| x 255, all pixels and channels).

Rows: mmbm augment (default: ``integrator="fast"``), mmbm exact, a 30-warp
average (OpenCV ``warpPerspective`` at 30 evenly spaced instants of the same
rotation, reflected border: the gyro-driven generators' method), and
albumentations' ``MotionBlur`` (a 21-tap line kernel, horizontal, centred:
one 2-D kernel for the whole image). mmbm's fast integrator is also timed on
the GPU (``backend="gpu"``, when an adapter exists). ``augment_batch`` of 16 is timed too. The blur maps are not asked for
(``return_maps=False``, the default): they are a measure, not the image.

Needs ``opencv-python-headless`` and ``albumentations`` (measurement only;
not test dependencies): ``python bench/augment_bench.py``.
"""

import os
import time

import numpy as np

import mmbm

W, H = 640, 480
EXPOSURE = 0.03
F_PX = 4.2548 / 0.00465  # thesis focal length, px
YAW = 20.0 / (F_PX * EXPOSURE)  # rad/s: about 20 px at the centre
MOTION = {"omega": [0.0, YAW, 0.0]}


def texture(seed=0):
    rng = np.random.default_rng(seed)
    j, i = np.mgrid[0:H, 0:W]
    smooth = 0.5 + 0.25 * np.sin(i * 0.11) * np.cos(j * 0.07)
    return (0.6 * smooth[..., None] + 0.4 * rng.random((H, W, 3))).astype(np.float32)


def timed(f, reps):
    f()  # warm-up (tables, thread pools)
    ts = []
    for _ in range(reps):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), f()


def err(a, b):
    e = np.abs(a.astype(np.float64) - b.astype(np.float64)) * 255.0
    return e.mean(), np.percentile(e, 99)


def warp30(img, n=30):
    import cv2

    k = np.array([[F_PX, 0, W / 2], [0, F_PX, H / 2], [0, 0, 1.0]])
    ki = np.linalg.inv(k)
    acc = np.zeros_like(img, dtype=np.float32)
    # Pixel centres at integers in OpenCV, at +0.5 in mmbm.
    sh = np.array([[1, 0, 0.5], [0, 1, 0.5], [0, 0, 1.0]])
    for m in range(n):
        t = ((m + 0.5) / n - 0.5) * EXPOSURE
        a = YAW * t
        r = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        # Image px -> frame px for a camera turned by R: K R^T K^-1.
        hm = np.linalg.inv(sh) @ k @ r.T @ ki @ sh
        acc += cv2.warpPerspective(img, hm, (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT_101)
    return acc / n


def main():
    img = texture()
    common = dict(motion=MOTION, exposure=EXPOSURE, centre=True, seed=0)
    rows = []
    t_fast, fast = timed(lambda: mmbm.augment(img, **common), 7)
    t_exact, exact = timed(lambda: mmbm.augment(img, integrator="exact", **common), 2)
    ref = exact["image"]
    rows.append(("mmbm augment (fast)", t_fast, *err(fast["image"], ref), f"{fast['samples']} warps"))
    rows.append(("mmbm exact", t_exact, 0.0, 0.0, f"{exact['samples']} warps"))
    # The GPU kernel (backend="gpu"; on a machine without a hardware GPU a
    # software adapter such as Mesa lavapipe, slower than the CPU there).
    try:
        mmbm.augment(img, backend="gpu", **common)  # compiles the kernel
        t_gpu, gpu = timed(lambda: mmbm.augment(img, backend="gpu", **common), 7)
        rows.append(("mmbm augment (fast, backend gpu)", t_gpu, *err(gpu["image"], ref), f"{gpu['samples']} warps"))
    except Exception as e:  # no adapter
        rows.append(("mmbm augment (fast, backend gpu)", float("nan"), float("nan"), float("nan"), f"no adapter: {e}"))
    # The 30-warp rotation must be the same motion: its mid homography is mmbm's.
    try:
        t_w, w30 = timed(lambda: warp30(img), 3)
        rows.append(("30-warp average (OpenCV)", t_w, *err(w30, ref), "30 warps"))
    except ImportError:
        rows.append(("30-warp average (OpenCV)", float("nan"), float("nan"), float("nan"), "cv2 missing"))
    try:
        import albumentations as A

        mb = A.MotionBlur(blur_limit=(21, 21), angle_range=(0, 0), direction_range=(0, 0), allow_shifted=False, p=1.0)
        t_a, alb = timed(lambda: mb(image=img)["image"], 7)
        rows.append((f"albumentations {A.__version__} MotionBlur", t_a, *err(alb, ref), "21-tap kernel"))
    except ImportError:
        rows.append(("albumentations MotionBlur", float("nan"), float("nan"), float("nan"), "not installed"))
    path = mmbm.augment(img, return_maps=True, **common)["maps"]["path_px"].mean()
    batch = np.stack([texture(s) for s in range(16)])
    t_b, b = timed(lambda: mmbm.augment_batch(batch, seed=0, **{k: v for k, v in common.items() if k != "seed"}), 3)
    print(f"mmbm augment bench, {W} x {H} float32 linear RGB, yaw {YAW:.4f} rad/s over {EXPOSURE} s "
          f"(mean path {path:.1f} px), {os.cpu_count()} CPUs")
    print("| method | s per image | mean error (/255) | p99 error (/255) | note |")
    print("|---|---|---|---|---|")
    for name, t, m, p, note in rows:
        print(f"| {name} | {t:.4f} | {m:.3f} | {p:.3f} | {note} |")
    print(f"augment_batch of 16: {t_b:.3f} s ({16 / t_b:.1f} images/s); "
          f"one image at a time: {16 * t_fast:.3f} s ({1 / t_fast:.1f} images/s)")


if __name__ == "__main__":
    main()
