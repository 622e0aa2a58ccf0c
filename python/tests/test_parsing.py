"""Issue 35 through the Python door: integer camera keys are never
truncated, a frame's NaN readout is "not a finite number", and a large
Gyroflow profile is read in linear time (or refused by its cap at once)."""

import json
import time

import numpy as np
import pytest

import mmbm


def profile():
    return {
        "calib_dimension": {"w": 1920, "h": 1080},
        "distortion_model": "opencv_fisheye",
        "fisheye_params": {
            "camera_matrix": [[1000.0, 0.0, 960.0], [0.0, 1000.0, 540.0], [0.0, 0.0, 1.0]],
            "distortion_coeffs": [0.01, 0.0, 0.0, 0.0],
        },
    }


@pytest.mark.parametrize("key", ["width", "height"])
def test_a_non_integral_size_is_refused_by_name(key):
    with pytest.raises(ValueError, match=f"camera.{key}: must be an integer, got 1.7"):
        mmbm.Camera(**{key: 1.7})
    # An integral float is that integer: the same camera as 640 x 480.
    assert mmbm.metric([1.0, 1.0, 1.0], camera=mmbm.Camera(width=640.0, height=480.0)) == mmbm.metric([1.0, 1.0, 1.0])


def test_other_integer_camera_keys_are_refused_by_name():
    with pytest.raises(ValueError, match=r"camera.noise.bits: must be an integer, got 10.5"):
        mmbm.Camera(noise={"phi_e_per_s": 5e4, "bits": 10.5})
    with pytest.raises(ValueError, match=r"camera.noise.seed: must be an integer"):
        mmbm.Camera(noise={"phi_e_per_s": 5e4, "seed": 0.5})


def test_frames_with_a_nan_readout_says_finite():
    t = np.arange(100) * 0.01
    w = np.tile([0.3, -0.2, 0.5], (100, 1))
    with pytest.raises(ValueError, match="readout_s: must be a finite number, got NaN"):
        mmbm.frames(t, w, [0.1, 0.2], 0.01, readout_s=[0.01, float("nan")])
    with pytest.raises(ValueError, match="exposure_s: must be a finite number, got NaN"):
        mmbm.frames(t, w, [0.1], float("nan"))
    with pytest.raises(ValueError, match="readout_s: must be >= 0 s, got -1"):
        mmbm.frames(t, w, [0.1], 0.01, readout_s=[-1.0])


def test_a_large_profile_is_read_fast(tmp_path):
    # At the cap (8192 entries), the last one the video's size: milliseconds
    # (each entry copied the whole profile: about 16 s).
    p = profile()
    n = 8192
    p["compatible_settings"] = [{"width": 2 * (k % 500) + 2, "height": 2 * (k % 7) + 2} for k in range(n)]
    path = tmp_path / "cap.json"
    path.write_text(json.dumps(p))
    start = time.perf_counter()
    c = mmbm.Camera.from_file(path)
    took = time.perf_counter() - start
    assert (c.width, c.height) == (1920, 1080)
    assert took < 2.0, took
    # The probe's 35,000 entries (under 1 MiB): refused by the cap at once,
    # naming the key and the count.
    p["compatible_settings"] = [{"width": 2 * (k % 4000) + 2, "height": 1080} for k in range(35000)]
    path = tmp_path / "big.json"
    path.write_text(json.dumps(p, separators=(",", ":")))
    assert path.stat().st_size < 1 << 20
    start = time.perf_counter()
    with pytest.raises(ValueError, match="compatible_settings.*35000"):
        mmbm.Camera.from_file(path)
    assert time.perf_counter() - start < 2.0


def test_integer_parameters_are_not_truncated():
    with pytest.raises(ValueError, match="seed: must be an integer, got 1.7"):
        mmbm.simulate(duration=0.1, seed=1.7)
    a = mmbm.simulate(duration=0.1, seed=2.0)
    b = mmbm.simulate(duration=0.1, seed=2)
    assert np.array_equal(a["omega"], b["omega"])
