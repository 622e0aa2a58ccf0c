"""The Python package against the CLI (same inputs, equal to the last digit),
a NumPy-only reference of the metric, shapes and dtypes, and bad inputs."""

import csv
import dataclasses
import io
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import mmbm

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("MMBM_BIN", str(ROOT / "target" / "release" / "mmbm"))


def cli(*args: str) -> str:
    r = subprocess.run([BIN, *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def fmt(v) -> str:
    return ",".join(repr(float(x)) for x in v)


RNG = np.random.default_rng(20261123)
TWISTS = [(RNG.normal(0, 1.5, 3), RNG.normal(0, 0.4, 3)) for _ in range(6)]


@pytest.mark.parametrize("method", ["riemann:8x6", "gauss:4", "exact:1e-10"])
def test_metric_equals_cli(method):
    for w, v in TWISTS:
        out = json.loads(cli("eval", "--omega", fmt(w), "--velocity", fmt(v), "--depth", "1.5", "--method", method, "--json"))
        got = mmbm.metric(w, v, depth=1.5, method=method)
        assert float(got) == out["mmbm_mm_s"], (w, v, method)


def numpy_mmbm_star(w, v, z, nu=8, nv=6, f=4.2548, p=0.00465, width=640, height=480):
    """docs/spec.md section 3 (thesis eq. 3.20) on the centres of an nu x nv grid (thesis MMBM*), mm/s."""
    su, sv = width * p, height * p
    u = (np.arange(nu) + 0.5) / nu * su - su / 2
    vv = (np.arange(nv) + 0.5) / nv * sv - sv / 2
    U, V = np.meshgrid(u, vv)
    wx, wy, wz = w
    vx, vy, vz = v
    du = wz * V - wy * f - (wy / f) * U**2 + (wx / f) * U * V - (f / z) * vx + (U / z) * vz
    dv = -wz * U + wx * f - (wy / f) * U * V + (wx / f) * V**2 - (f / z) * vy + (V / z) * vz
    return float(np.mean(np.hypot(du, dv)))


def test_metric_matches_numpy_reference():
    ws = np.array([w for w, _ in TWISTS])
    vs = np.array([v for _, v in TWISTS])
    got = mmbm.metric(ws, vs, depth=2.0)
    want = np.array([numpy_mmbm_star(w, v, 2.0) for w, v in TWISTS])
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_shapes_dtypes_and_broadcasting():
    assert mmbm.metric([1.0, 1.0, 1.0]).shape == ()
    assert mmbm.metric(np.ones((5, 3))).shape == (5,)
    # one rotation, five velocities
    m = mmbm.metric([0.1, 0.2, 0.3], np.linspace(0, 1, 15).reshape(5, 3), depth=1.0)
    assert m.shape == (5,) and m.dtype == np.float64
    assert np.all(np.diff(m) != 0)
    f = mmbm.flow_field([0.1, -0.2, 0.3], camera=mmbm.Camera().with_resolution(64, 48))
    assert f.shape == (48, 64, 2) and f.dtype == np.float32
    img, maps = mmbm.render(omega=[0.3, -0.2, 0.5], resolution=(32, 24), quality="fast")
    assert img.shape == (24, 32, 3) and img.dtype == np.float32
    assert set(maps) == {"path_px", "disp_px", "speed_px_s"} and maps["path_px"].shape == (24, 32)


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    d = tmp_path_factory.mktemp("walk")
    p = d / "walk.csv"
    cli("simulate", "--gait", "moderate", "--duration", "3", "--seed", "5", "--out", str(p))
    return p


def test_simulate_and_read_gyro_equal_cli(walk):
    g = mmbm.simulate("moderate", duration=3, seed=5)
    r = mmbm.read_gyro(walk)
    for k in ("t", "omega", "velocity"):
        assert np.array_equal(g[k], r[k]), k
    rows = list(csv.reader(io.StringIO(walk.read_text())))
    assert rows[0][:4] == ["t", "wx", "wy", "wz"]
    assert np.array_equal(r["t"], [float(x[0]) for x in rows[1:]])


def test_series_equals_cli(walk):
    g = mmbm.read_gyro(walk)
    for method in ["riemann:8x6", "gauss:4x3"]:
        got = mmbm.series(g["t"], g["omega"], method=method)
        rows = list(csv.reader(io.StringIO(cli("series", "--gyro", str(walk), "--method", method))))
        assert rows[0][:2] == ["t", "mmbm_mm_s"]
        assert np.array_equal(got, [float(x[1]) for x in rows[1:]])


def test_trigger_equals_cli(walk):
    g = mmbm.read_gyro(walk)
    m = mmbm.series(g["t"], g["omega"])
    pols = ["fixed:5", "threshold:0.4", "oracle:0.4", "deadline:5", "phase:0.4", "fixed:5+exp:2:0.01"]
    got = mmbm.trigger(g["t"], m, pols, exposure=0.07)
    args = ["trigger", "--gyro", str(walk), "--exposure", "0.07"]
    for p in pols:
        args += ["--policy", p]
    rows = list(csv.DictReader(io.StringIO(cli(*args))))
    assert len(got) == len(rows) > 0
    for a, b in zip(got, rows):
        assert a["policy"] == b["policy"]
        for k in ("trigger_t", "exposure_start", "exposure_end", "mmbm_trigger_mm_s", "mmbm_exposure_mm_s", "gain"):
            assert a[k] == float(b[k]), k
        assert int(a["kept"]) == int(b["kept"])
    # Exposure control chose shorter exposures with a higher gain somewhere.
    assert any(a["gain"] > 1.0 for a in got if a["policy"].endswith("+exp:2:0.01"))


def test_render_equals_cli(tmp_path):
    out = tmp_path / "r.exr"
    maps = tmp_path / "m.exr"
    cli(
        "render", "--omega", "0.3,-0.2,0.5", "--velocity", "0.1,0,0.05", "--exposure", "0.04",
        "--target", "blobs:0.5", "--distance", "1.5", "--tilt", "10,-5", "--resolution", "96x72",
        "--backend", "cpu", "--out", str(out), "--maps", str(maps),
    )
    img, m = mmbm.render(
        omega=[0.3, -0.2, 0.5], velocity=[0.1, 0, 0.05], exposure=0.04, target="blobs:0.5",
        distance=1.5, tilt=(10, -5), resolution=(96, 72), backend="cpu",
    )
    e = mmbm.read_exr(out)
    assert np.array_equal(img, np.stack([e["R"], e["G"], e["B"]], axis=-1))
    em = mmbm.read_exr(maps)
    for k in ("path_px", "disp_px", "speed_px_s"):
        assert np.array_equal(m[k], em[k]), k


def test_flow_field_equals_cli(tmp_path):
    out = tmp_path / "f.exr"
    cli("flow", "--omega", "0.4,-0.1,0.2", "--velocity", "0.1,0,0", "--depth", "2", "--sensor", "80x60", "--out", str(out))
    e = mmbm.read_exr(out)
    f = mmbm.flow_field([0.4, -0.1, 0.2], [0.1, 0, 0], depth=2, camera=mmbm.Camera().with_resolution(80, 60))
    # The CLI runs the GPU kernel; the package the CPU twin: the twins agree
    # to f32 rounding (cli/tests/camera/gpu_flow.rs).
    np.testing.assert_allclose(f[..., 0], e["flow.u"], rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(f[..., 1], e["flow.v"], rtol=1e-5, atol=1e-3)


def test_camera_file(tmp_path):
    p = tmp_path / "cam.toml"
    p.write_text("focal_mm = 3.0\npitch_mm = 0.002\nwidth = 100\nheight = 80\n")
    c = mmbm.Camera.from_file(p)
    assert (c.focal_mm, c.pitch_x_mm, c.width, c.height, c.cx, c.cy) == (3.0, 0.002, 100, 80, 50.0, 40.0)
    out = json.loads(cli("eval", "--omega", "1,0.5,0.2", "--camera", str(p), "--json"))
    assert float(mmbm.metric([1, 0.5, 0.2], camera=c)) == out["mmbm_mm_s"]


def test_real_camera_file_and_render(tmp_path):
    # Every docs/spec.md section 9 key survives Camera.from_file, and rendering with it equals
    # the CLI (rolling shutter, distortion and seeded noise).
    p = ROOT / "tests" / "fixtures" / "camera" / "opencv.toml"
    c = mmbm.Camera.from_file(p)
    assert c.readout_s == 0.016 and c.readout_direction == "top-to-bottom"
    assert c.distortion["model"] == "opencv" and c.distortion["k1"] == -0.28
    assert c.noise["phi_e_per_s"] == 50000 and c.noise["bits"] == 10
    assert c.lens == {"f_number": 2.0, "focus_m": 1.5}
    out = json.loads(cli("eval", "--omega", "1,0.5,0.2", "--camera", str(p), "--method", "gauss:4", "--json"))
    assert float(mmbm.metric([1, 0.5, 0.2], camera=c, method="gauss:4")) == out["mmbm_mm_s"]
    cam = dataclasses.replace(c, lens=None).with_resolution(64, 48)
    q = tmp_path / "cam.json"
    q.write_text(json.dumps({
        "focal_mm": cam.focal_mm, "pitch_mm": cam.pitch_x_mm, "width": 64, "height": 48,
        "readout_s": cam.readout_s, "distortion": cam.distortion, "noise": cam.noise,
    }))
    r = tmp_path / "r.exr"
    cli("render", "--omega", "0.3,-0.2,0.5", "--exposure", "0.02", "--target", "checker:0.05",
        "--distance", "1", "--camera", str(q), "--backend", "cpu", "--out", str(r))
    img, _ = mmbm.render(omega=[0.3, -0.2, 0.5], exposure=0.02, target="checker:0.05", distance=1,
                         camera=cam, backend="cpu", maps=False)
    e = mmbm.read_exr(r)
    assert np.array_equal(img, np.stack([e["R"], e["G"], e["B"]], axis=-1))


def test_frames_equal_cli(tmp_path):
    g = ROOT.parent / "shared" / "data" / "running_phone"
    if not g.exists():
        pytest.skip("../shared/data is not beside the checkout")
    cam_file = ROOT / "examples" / "cameras" / "running_phone.toml"
    out = list(csv.DictReader(io.StringIO(cli(
        "frames", "--gyro", str(g / "gyro.csv"), "--frames", str(g / "frames.csv"), "--camera", str(cam_file)))))
    log = mmbm.read_gyro(g / "gyro.csv")
    rows = [r for r in csv.reader(l for l in open(g / "frames.csv") if not l.startswith("#"))][1:]
    fr = np.array(rows, dtype=float)
    got = mmbm.frames(log["t"], log["omega"], fr[:, 0], fr[:, 1], fr[:, 2], camera=mmbm.Camera.from_file(cam_file))
    assert len(out) == len(fr)
    for k, o in enumerate(out):
        if o["exposure_mmbm_mm_s"] == "":
            assert np.isnan(got["exposure_mmbm_mm_s"][k])
            continue
        assert got["exposure_mmbm_mm_s"][k] == float(o["exposure_mmbm_mm_s"])
        assert got["blur_px"][k] == pytest.approx(float(o["blur_px"]), rel=1e-15)
        assert got["start_mmbm_mm_s"][k] == float(o["start_mmbm_mm_s"])


def test_frame_maps_equal_cli(tmp_path):
    g = ROOT.parent / "shared" / "data" / "running_phone"
    if not g.exists():
        pytest.skip("../shared/data is not beside the checkout")
    cam_file = tmp_path / "cam.toml"
    cam_file.write_text("focal_mm = 0.15118\npitch_mm = 0.001\nwidth = 192\nheight = 108\nreadout_s = 0.01598\n")
    table = tmp_path / "frames.csv"
    table.write_text("t_start,exposure_s\n5.258,0.0013\n99.0,0.001\n")
    d = tmp_path / "maps"
    cli("frames", "--gyro", str(g / "gyro.csv"), "--frames", str(table), "--camera", str(cam_file),
        "--maps", str(d), "--maps-format", "float", "--out", str(tmp_path / "f.csv"))
    log = mmbm.read_gyro(g / "gyro.csv")
    got = mmbm.frames(log["t"], log["omega"], [5.258, 99.0], [0.0013, 0.001],
                      camera=mmbm.Camera.from_file(cam_file), maps=True)
    assert got["maps"][1] is None and not (d / "frame_000002.exr").exists()
    e = mmbm.read_exr(d / "frame_000001.exr")
    assert sorted(got["maps"][0]) == sorted(e) == sorted(["disp.u", "disp.v", "path_px", "flow.u", "flow.v"])
    for name, a in got["maps"][0].items():
        assert a.shape == (108, 192) and a.dtype == np.float32
        assert np.array_equal(a, e[name]), name
    assert np.all(got["maps"][0]["path_px"] >= np.hypot(e["disp.u"], e["disp.v"]) - 1e-6)
    assert np.mean(got["maps"][0]["path_px"]) > 0.01


# A 1 s log at 200 Hz for the frame cases.
T = np.arange(200) * 0.005
W = np.tile([0.1, 0.2, 0.3], (200, 1))


@pytest.mark.parametrize(
    "call, exc, words",
    [
        (lambda: mmbm.metric([1, 2]), ValueError, "omega"),
        (lambda: mmbm.metric([1, 1, 1], method="simpson"), ValueError, "simpson"),
        (lambda: mmbm.metric([0, 0, 0], [0, 0, 1]), ValueError, "depth"),
        (lambda: mmbm.metric([0, 0, 0], [0, 0, 1], plane=[0, 0, 1, -1]), ValueError, "plane"),
        (lambda: mmbm.metric([float("nan"), 0, 0]), ValueError, "finite"),
        (lambda: mmbm.Camera(focal_mm=0), ValueError, "focal"),
        (lambda: mmbm.Camera.from_file("/nonexistent/cam.toml"), OSError, "nonexistent"),
        (lambda: mmbm.read_gyro("/nonexistent.csv"), OSError, "nonexistent"),
        (lambda: mmbm.series([0, 1], np.zeros((3, 3))), ValueError, "rows"),
        (lambda: mmbm.series([0, 0], np.zeros((2, 3))), ValueError, "t"),
        (lambda: mmbm.trigger([0, 1], [0, 0], "fixed:1e9", 0.05), ValueError, "1000"),
        (lambda: mmbm.render(omega=[0, 0, 0], velocity=[0, 0, 5], exposure=0.5, resolution=(8, 6)), ValueError, "target plane"),
        (lambda: mmbm.render(omega=[0, 0, 0], target="image:/nonexistent.png:1"), OSError, "nonexistent"),
        (lambda: mmbm.simulate("moonwalk"), ValueError, "moonwalk"),
        (lambda: mmbm.read_exr("/nonexistent.exr"), OSError, "nonexistent"),
        # Issue 23 items 3 and 4: the library's checks, through Python.
        (lambda: mmbm.read_gyro("/dev/zero"), OSError, "character device"),
        (lambda: mmbm.flow_field([0.1, 0, 0], camera=mmbm.Camera(width=65535, height=65535)), ValueError, "67108864"),
        (lambda: mmbm.render(omega=[0.1, 0, 0], resolution=(-1, 5)), ValueError, "resolution"),
        (lambda: mmbm.frames(T, W, [0.1], [-0.5]), ValueError, "exposure_s"),
        (lambda: mmbm.frames(T, W, [0.1], [float("nan")]), ValueError, "exposure_s"),
        (lambda: mmbm.frames(T, W, [0.1], [0.02], [-0.5]), ValueError, "readout_s"),
        (lambda: mmbm.frames(T, W, [0.1], [0.02], [float("nan")]), ValueError, "readout_s"),
        (lambda: mmbm.frames(T, W, [float("nan")], [0.02]), ValueError, "t_start"),
    ],
)
def test_bad_inputs_raise(call, exc, words):
    with pytest.raises(exc) as e:
        call()
    assert words in str(e.value)
