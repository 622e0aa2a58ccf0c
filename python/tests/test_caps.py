"""Caps checked before the work (issue 35), through the Python doors: the
blur maps' pixels (`frames(maps=True)`) and a sensor's light; each raises
quickly instead of taking the interpreter down or spinning."""
import dataclasses
import time

import numpy as np
import pytest

import mmbm

MAP_CAP = 1 << 25  # mmbm::limits::MAX_MAP_PIXELS
LIGHT_CAP = 1e12  # mmbm::limits::MAX_LIGHT_E_PER_S


def _log():
    t = np.arange(601) / 600.0
    return t, np.tile([0.3, 0.2, 0.1], (t.size, 1))


@pytest.mark.parametrize("size", [(100_000, 100_000), (8193, 8192)])
def test_frames_maps_on_a_huge_camera_raise(size):
    t, w = _log()
    cam = mmbm.Camera().with_resolution(*size)
    start = time.monotonic()
    with pytest.raises(ValueError, match=f"{size[0]}x{size[1]}.*{MAP_CAP}"):
        mmbm.frames(t, w, [0.1], 0.02, camera=cam, maps=True)
    assert time.monotonic() - start < 10


def test_frames_maps_under_the_cap_still_work():
    t, w = _log()
    out = mmbm.frames(t, w, [0.1], 0.02, camera=mmbm.Camera().with_resolution(16, 12), maps=True)
    assert out["maps"][0]["path_px"].shape == (12, 16)


def _render(cam, exposure):
    return mmbm.render(omega=[0, 0, 0], exposure=exposure, target="checker:0.02", distance=1,
                       camera=cam, backend="cpu", maps=False)


@pytest.mark.parametrize("light", [1e308, 1.0000001e12, float("inf")])
def test_a_huge_light_raises(light):
    # Refused where the camera is made (and by every call given one).
    start = time.monotonic()
    with pytest.raises(ValueError, match="phi_e_per_s"):
        cam = dataclasses.replace(mmbm.Camera().with_resolution(32, 24), noise={"phi_e_per_s": light})
        _render(cam, 0.05)
    assert time.monotonic() - start < 10
    if light != float("inf"):
        with pytest.raises(ValueError, match="above the cap of 1e12"):
            mmbm.Camera(noise={"phi_e_per_s": light})


def test_an_absurd_mean_under_the_light_cap_saturates_quickly():
    # 1e12 e-/s over 1e294 s: a mean near 1e305 e-, where the exact Poisson
    # sampler spins; the bounded one saturates the checker's white squares.
    cam = dataclasses.replace(mmbm.Camera().with_resolution(32, 24), noise={"phi_e_per_s": LIGHT_CAP})
    start = time.monotonic()
    img, _ = _render(cam, 1e294)
    assert time.monotonic() - start < 20
    assert (img == 1.0).mean() > 0.25
