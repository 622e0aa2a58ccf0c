"""mmbm.read_gyro on a camera's own files: the fixtures of
tests/fixtures/telemetry/ (built by cli/tests/logs/telemetry.rs from known rates),
read with their metadata; bad files raise with the file and the place."""

import math
import os

import numpy as np
import pytest

import mmbm

FIX = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "fixtures", "telemetry")


def fix(name):
    return os.path.join(FIX, name)


def test_gopro_mp4_rates_and_frame_rate():
    g = mmbm.read_gyro(fix("gopro_hero.mp4"))
    assert g["format"] == "gopro-mp4" and g["orientation"] == "action-cam"
    assert g["fps"] == pytest.approx(30.0)
    assert g["t"].shape == (600,) and g["omega"].shape == (600, 3)
    # Payload k, sample i: (0.5 - 0.125 k, (i - 250) / 1000, 0.125 k) rad/s at k + i / 200 s.
    k, i = 2, 17
    n = k * 200 + i
    assert g["t"][n] == pytest.approx(k + i / 200, abs=1e-12)
    np.testing.assert_allclose(g["omega"][n], [0.5 - 0.125 * k, (i - 250) / 1000, 0.125 * k], atol=1e-12)


def test_gyroflow_project_samples_offsets_readout():
    p = mmbm.read_gyro(fix("project.gyroflow"))
    assert p["format"] == "gyroflow-project"
    assert p["readout_s"] == pytest.approx(0.0165)
    assert p["fps"] == pytest.approx(29.97)
    assert p["offsets"] == [(0.0, 0.02)]
    assert '"calib_dimension"' in p["lens_profile"]
    # Sample 3: gyro (10.75, -20, 15) deg/s, orientation XYZ -> (-gy, -gx, -gz) in the camera frame.
    np.testing.assert_allclose(p["omega"][3], np.radians([20.0, -10.75, -15.0]), atol=1e-12)
    assert p["t"][3] == pytest.approx(0.015 + 0.02, abs=1e-12)


def test_phone_apps_with_a_preset():
    for name in ["sensor_logger_Gyroscope.csv", "phyphox_Gyroscope rotation rate.csv"]:
        a = mmbm.read_gyro(fix(name), orientation="phone-back-portrait")
        assert a["t"][0] == pytest.approx(0.25)
        # Device (0.5, -1.25, 2) -> back camera, portrait: (x, -y, -z).
        np.testing.assert_allclose(a["omega"][0], [0.5, 1.25, -2.0], atol=1e-12)
        m = mmbm.series(a["t"], a["omega"])
        assert m.shape == (100,) and np.all(np.isfinite(m)) and np.all(m > 0)


def test_bad_files_raise_naming_file_and_place(tmp_path):
    cut = tmp_path / "cut.mp4"
    data = open(fix("gopro_hero.mp4"), "rb").read()
    cut.write_bytes(data[: len(data) - 40])
    with pytest.raises(ValueError, match=r"cut\.mp4.*moov"):
        mmbm.read_gyro(cut)
    bad = tmp_path / "bad.gyroflow"
    bad.write_text('{"gyro_source": {"raw_imu": "compressed!"}}')
    with pytest.raises(ValueError, match=r"bad\.gyroflow.*raw_imu.*compressed"):
        mmbm.read_gyro(bad)
    with pytest.raises(ValueError, match="phone-back-portrait"):
        mmbm.read_gyro(fix("project.gyroflow"), orientation="sideways")


def test_plain_logs_read_as_before(tmp_path):
    p = tmp_path / "g.csv"
    p.write_text("t,wx,wy,wz\n0,1,2,3\n0.01,1,2,3\n")
    g = mmbm.read_gyro(p)
    assert g["format"] == "log" and "fps" not in g
    np.testing.assert_array_equal(g["omega"], [[1, 2, 3], [1, 2, 3]])
    assert math.isclose(g["t"][1], 0.01)
