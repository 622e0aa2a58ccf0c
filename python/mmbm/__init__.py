"""mmbm: camera motion blur from NumPy.

The MMBM metric (mean image-plane flow speed over the sensor, mm/s), per-pixel
flow fields (px/s), a ground-truth motion-blur renderer, gait simulation and
trigger policies, over the Rust library of the ``mmbm`` command-line tool.

Units: angular velocity rad/s, linear velocity m/s, distances m, times s,
flow px/s, MMBM mm/s (divide by the pixel pitch for px/s). Camera frame: x
right, y down, z along the optical axis. Long work releases the GIL. Errors
raise ``ValueError`` (bad values) or ``OSError`` (files) with the library's
message.

>>> import mmbm, numpy as np
>>> float(mmbm.metric([1.0, 1.0, 1.0], method="exact:1e-9"))  # doctest: +ELLIPSIS
6.25637772...
"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _mmbm

__all__ = [
    "Camera",
    "metric",
    "series",
    "frames",
    "read_gyro",
    "flow_field",
    "render",
    "simulate",
    "trigger",
    "read_exr",
    "choose_frames",
    "augment",
    "augment_batch",
    "BlurDataset",
]

PathLike = Union[str, "os.PathLike[str]"]
ArrayLike = Any


# The thesis camera, from its one definition in the library (``Camera::thesis``),
# as the keys of a camera file.
_THESIS: Dict[str, Any] = json.loads(_mmbm.camera_thesis())


@dataclass(frozen=True)
class Camera:
    """A camera (the keys of mmbm's camera files, docs/spec.md sections 1 and 9).

    ``focal_mm``: focal length, mm; ``pitch_x_mm``, ``pitch_y_mm``: pixel
    pitch, mm; ``width``, ``height``: sensor size, px; ``cx``, ``cy``:
    principal point, px from the top-left corner (default: the centre);
    ``skew``: px. ``Camera()`` is the thesis camera (4.2548 mm, 4.65 um,
    640 x 480). The real camera: ``readout_s`` (rolling shutter, s; 0 =
    global) and ``readout_direction`` ("top-to-bottom", ...), ``distortion``
    (e.g. ``{"model": "opencv", "k1": -0.28}`` or ``{"model": "fisheye",
    "k1": 0.03}``), ``noise`` (``{"phi_e_per_s": 50000, ...}``), ``lens``
    (``{"f_number": 2.0, "focus_m": 1.5}``).
    """

    focal_mm: float = _THESIS["focal_mm"]
    pitch_x_mm: float = _THESIS["pitch_x_mm"]
    pitch_y_mm: float = _THESIS["pitch_y_mm"]
    width: int = _THESIS["width"]
    height: int = _THESIS["height"]
    cx: Optional[float] = None
    cy: Optional[float] = None
    skew: float = 0.0
    readout_s: float = 0.0
    readout_direction: str = "top-to-bottom"
    distortion: Optional[dict] = None
    noise: Optional[dict] = None
    lens: Optional[dict] = None

    def __post_init__(self) -> None:
        if self.cx is None:
            object.__setattr__(self, "cx", self.width / 2.0)
        if self.cy is None:
            object.__setattr__(self, "cy", self.height / 2.0)
        _mmbm.camera_check(self._spec())

    @classmethod
    def from_file(cls, path: PathLike) -> "Camera":
        """Reads a camera file (TOML or JSON, as ``mmbm --camera FILE``)."""
        # Every key of the file's camera, named as this class's fields.
        return cls(**json.loads(_mmbm.camera_from_file(os.fspath(path))))

    def with_resolution(self, width: int, height: int) -> "Camera":
        """Same focal length and pitch, another size, principal point at the centre."""
        return dataclasses.replace(self, width=width, height=height, cx=None, cy=None)

    def _spec(self) -> Dict[str, Any]:
        """The camera as the native module takes it: a camera file's keys."""
        x: Dict[str, Any] = {
            "focal_mm": float(self.focal_mm),
            "pitch_x_mm": float(self.pitch_x_mm),
            "pitch_y_mm": float(self.pitch_y_mm),
            # As given: the native side refuses a non-integral width (1.7), by name.
            "width": self.width,
            "height": self.height,
            "cx": float(self.cx),  # type: ignore[arg-type]
            "cy": float(self.cy),  # type: ignore[arg-type]
            "skew": float(self.skew),
            "readout_s": float(self.readout_s),
            "readout_direction": self.readout_direction,
        }
        for k in ("distortion", "noise", "lens"):
            v = getattr(self, k)
            if v is not None:
                x[k] = v
        return x


def _int(x: Any, name: str) -> int:
    """An integer parameter: an int, or a float of integral value (``2.0``);
    ``1.7`` is a ``ValueError`` naming ``name``, never truncated to 1."""
    if isinstance(x, (float, np.floating)) and not float(x).is_integer():
        raise ValueError(f"{name}: must be an integer, got {x}")
    return int(x)


def _cam(camera: Optional[Camera]) -> Dict[str, Any]:
    return (camera or Camera())._spec()


def _log(t: ArrayLike, omega: ArrayLike) -> Tuple[np.ndarray, np.ndarray]:
    """A log's times (N,) s, checked increasing, and its (N, 3) angular velocities."""
    tt = np.ascontiguousarray(np.asarray(t, dtype=np.float64).ravel())
    if not (np.all(np.isfinite(tt)) and np.all(np.diff(tt) > 0)):
        raise ValueError("t: times must be finite and strictly increasing (s)")
    w = _rows3(omega, "omega")
    if w.shape[0] != tt.shape[0]:
        raise ValueError(f"omega has {w.shape[0]} rows for {tt.shape[0]} times")
    return tt, w


def _rows3(x: ArrayLike, name: str) -> np.ndarray:
    a = np.ascontiguousarray(np.asarray(x, dtype=np.float64))
    if a.ndim == 1:
        a = a.reshape(1, -1)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name}: expected shape (3,) or (N, 3), got {np.shape(x)}")
    return a


def _plane(depth: Optional[float], plane: Optional[Sequence[float]]) -> Optional[np.ndarray]:
    if depth is not None and plane is not None:
        raise ValueError("give depth or plane, not both")
    if depth is not None:
        return np.array([0.0, 0.0, 1.0, float(depth)])
    if plane is not None:
        p = np.asarray(plane, dtype=np.float64).ravel()
        if p.shape != (4,):
            raise ValueError("plane: expected (nx, ny, nz, d)")
        return p
    return None


def metric(
    omega: ArrayLike,
    velocity: Optional[ArrayLike] = None,
    depth: Optional[float] = None,
    plane: Optional[Sequence[float]] = None,
    method: str = "riemann:8x6",
    camera: Optional[Camera] = None,
) -> np.ndarray:
    """MMBM in mm/s of twists: ``omega`` (rad/s) of shape (3,) or (N, 3),
    ``velocity`` (m/s) broadcast against it; translation needs ``depth`` (m,
    a fronto-parallel plane) or ``plane`` = (nx, ny, nz, d) with n.X = d.
    ``method``: ``riemann[:NUxNV]`` (the thesis's MMBM*), ``gauss[:N]``,
    ``exact[:TOL]``. Returns shape () for one twist, (N,) for N."""
    one = np.ndim(omega) == 1 and (velocity is None or np.ndim(velocity) == 1)
    w = _rows3(omega, "omega")
    v = _rows3(np.zeros(3) if velocity is None else velocity, "velocity")
    w, v = np.broadcast_arrays(w, v)
    out = _mmbm.metric(_cam(camera), np.ascontiguousarray(w), np.ascontiguousarray(v), _plane(depth, plane), method)
    return out.reshape(()) if one else out


def series(
    t: ArrayLike,
    omega: ArrayLike,
    velocity: Optional[ArrayLike] = None,
    depth: Optional[ArrayLike] = None,
    plane: Optional[Sequence[float]] = None,
    method: str = "riemann:8x6",
    camera: Optional[Camera] = None,
) -> np.ndarray:
    """MMBM (mm/s) of every sample of a log: ``t`` (s, increasing, shape
    (N,)), ``omega`` (N, 3) rad/s, optional ``velocity`` (N, 3) m/s with a
    per-sample ``depth`` (N,) m or a ``plane``. The same as ``mmbm series``.
    Arrays from ``telemetry_parser`` work as they are (see docs/python.md)."""
    tt, w = _log(t, omega)
    v = None if velocity is None else _rows3(velocity, "velocity")
    if v is not None and v.shape[0] != tt.shape[0]:
        raise ValueError(f"velocity has {v.shape[0]} rows for {tt.shape[0]} times")
    d = None
    if depth is not None:
        d = np.ascontiguousarray(np.broadcast_to(np.asarray(depth, dtype=np.float64), tt.shape))
    return _mmbm.series(_cam(camera), tt, w, v, d, _plane(None, plane), method)


def frames(
    t: ArrayLike,
    omega: ArrayLike,
    t_start: ArrayLike,
    exposure_s: ArrayLike,
    readout_s: Optional[ArrayLike] = None,
    method: str = "riemann:8x6",
    camera: Optional[Camera] = None,
    maps: bool = False,
) -> Dict[str, Any]:
    """Exposure MMBM of every video frame (docs/spec.md section 9: each line over its own
    rolling-shutter window), as ``mmbm frames``: ``t`` (N,) s and ``omega``
    (N, 3) rad/s of the log; per frame ``t_start`` (the first line's
    exposure start, s), ``exposure_s`` and ``readout_s`` (default: the
    camera's ``readout_s``), broadcast to one shape. Returns
    ``{"exposure_mmbm_mm_s", "blur_px", "start_mmbm_mm_s"}`` (NaN where a
    frame's window leaves the log). ``telemetry_parser``'s
    ``frame_readout_time()`` (ms) / 1000 is a ``readout_s``.

    With ``maps=True`` also ``"maps"``: per frame the per-pixel blur fields
    of ``mmbm frames --maps`` as ``{"disp.u", "disp.v", "path_px", "flow.u",
    "flow.v"}`` float32 arrays of the camera's (height, width) (px, px/s; NaN
    beyond the lens's radial limit), or ``None`` where the frame's span
    leaves the log or crosses a gap in it."""
    tt, w = _log(t, omega)
    ts = np.asarray(t_start, dtype=np.float64).ravel()
    es = np.ascontiguousarray(np.broadcast_to(np.asarray(exposure_s, dtype=np.float64), ts.shape))
    rs = None
    if readout_s is not None:
        rs = np.ascontiguousarray(np.broadcast_to(np.asarray(readout_s, dtype=np.float64), ts.shape))
    cam = camera or Camera()
    e, blur, s0 = _mmbm.frames(cam._spec(), tt, w, np.ascontiguousarray(ts), es, rs, method)
    out: Dict[str, Any] = {
        "exposure_mmbm_mm_s": e,
        "blur_px": blur,
        "start_mmbm_mm_s": s0,
    }
    if maps:
        names = ("disp.u", "disp.v", "path_px", "flow.u", "flow.v")
        out["maps"] = [
            None if m is None else dict(zip(names, m))
            for m in _mmbm.frame_maps(cam._spec(), tt, w, np.ascontiguousarray(ts), es, rs)
        ]
    return out


def read_gyro(
    path: PathLike,
    time_unit: str = "s",
    angle_unit: str = "rad",
    imu_rotation: Optional[Sequence[float]] = None,
    time_offset: float = 0.0,
    topic: Optional[str] = None,
    orientation: Optional[str] = None,
) -> Dict[str, Any]:
    """Reads a gyro log (CSV ``t,wx,wy,wz[,vx,vy,vz][,depth]``, a Gyroflow
    ``.gcsv``, a ROS 2 MCAP file with ``topic``, a phone's IMU rows) or a
    camera's own file (a GoPro MP4, a Gyroflow ``.gyroflow`` project,
    Sensor Logger's or phyphox's gyroscope CSV): ``{"t": (N,) s, "omega":
    (N, 3) rad/s[, "velocity": (N, 3) m/s][, "depth": (N,) m]}`` in the
    camera frame, with ``"format"`` and what the file says (``readout_s``,
    ``fps``, ``offsets``, ``lens_profile`` as JSON text, ``device``,
    ``orientation``). ``orientation``: a device-to-camera preset
    (``phone-back-portrait``, ``phone-back-landscape``, ``action-cam``, ...;
    docs/frames.md), applied before ``imu_rotation``."""
    rot = None if imu_rotation is None else ",".join(repr(float(x)) for x in np.ravel(imu_rotation))
    return _mmbm.read_camera(os.fspath(path), time_unit, angle_unit, rot, float(time_offset), topic, orientation)


def flow_field(
    omega: ArrayLike,
    velocity: Optional[ArrayLike] = None,
    depth: Optional[float] = None,
    plane: Optional[Sequence[float]] = None,
    camera: Optional[Camera] = None,
    backend: str = "cpu",
) -> np.ndarray:
    """The image-plane flow (px/s) at every pixel centre: float32 array of
    shape (H, W, 2), ``[..., 0]`` along x (right), ``[..., 1]`` along y
    (down). ``backend``: ``cpu`` (the CPU twin), ``gpu`` or ``auto``."""
    w = [float(x) for x in np.asarray(omega, dtype=np.float64).ravel()]
    v = [0.0, 0.0, 0.0] if velocity is None else [float(x) for x in np.asarray(velocity, dtype=np.float64).ravel()]
    if len(w) != 3 or len(v) != 3:
        raise ValueError("omega and velocity: expected 3 values each")
    return _mmbm.flow_field(_cam(camera), w, v, _plane(depth, plane), backend)


def render(
    omega: Optional[ArrayLike] = None,
    velocity: Optional[ArrayLike] = None,
    exposure: float = 0.05,
    target: str = "checker:0.02",
    distance: float = 1.0,
    tilt: Sequence[float] = (0.0, 0.0),
    offset: Sequence[float] = (0.0, 0.0),
    background: Optional[Sequence[float]] = None,
    gyro: Optional[Dict[str, np.ndarray]] = None,
    at: Optional[float] = None,
    use_velocity: bool = False,
    resolution: Optional[Tuple[int, int]] = None,
    quality: str = "default",
    integrator: str = "auto",
    backend: str = "cpu",
    seed: int = 0,
    maps: bool = True,
    sharp: bool = False,
    camera: Optional[Camera] = None,
) -> Tuple[np.ndarray, Optional[Dict[str, np.ndarray]]]:
    """Ground-truth motion blur of a planar target, as ``mmbm render``.

    Motion: a constant twist (``omega`` rad/s, ``velocity`` m/s) for
    ``exposure`` s, or a window of a log (``gyro`` = a ``read_gyro`` dict,
    exposure starting at ``at`` s). Target: ``checker:S``, ``blobs[:SCALE]``
    or ``image:PATH:WIDTH_M`` at ``distance`` m, ``tilt`` (deg about x, y),
    ``offset`` (m), ``background`` (linear RGB). Returns ``(image, maps)``:
    linear RGB float32 (H, W, 3) and, with ``maps``, ``{"path_px",
    "disp_px", "speed_px_s"}`` (H, W) float32. ``sharp=True`` renders the
    frame at exposure start instead."""
    cam = camera or Camera()
    if resolution is not None:
        cam = cam.with_resolution(_int(resolution[0], "resolution[0]"), _int(resolution[1], "resolution[1]"))
    w = None if omega is None else [float(x) for x in np.asarray(omega, dtype=np.float64).ravel()]
    v = [0.0, 0.0, 0.0] if velocity is None else [float(x) for x in np.asarray(velocity, dtype=np.float64).ravel()]
    bg = None if background is None else [float(x) for x in background]
    g = None
    if gyro is not None:
        g = {k: np.asarray(gyro[k], dtype=np.float64) for k in ("t", "omega", "velocity") if k in gyro}
    return _mmbm.render(
        cam._spec(),
        target,
        float(distance),
        [float(x) for x in tilt],
        [float(x) for x in offset],
        bg,
        float(exposure),
        w,
        v,
        g,
        None if at is None else float(at),
        bool(use_velocity),
        quality,
        integrator,
        backend,
        _int(seed, "seed"),
        bool(maps),
        bool(sharp),
    )


def simulate(
    gait: str = "moderate",
    duration: float = 16.0,
    seed: int = 0,
    rate: float = 600.0,
    config: Optional[PathLike] = None,
) -> Dict[str, np.ndarray]:
    """A seeded legged-gait log, as ``mmbm simulate``: ``{"t": (N,) s,
    "omega": (N, 3) rad/s, "velocity": (N, 3) m/s}``. ``gait``: slow,
    moderate or fast; ``config``: a gait TOML file over the preset."""
    return _mmbm.simulate(gait, float(duration), float(rate), _int(seed, "seed"), None if config is None else os.fspath(config))


def trigger(
    t: ArrayLike,
    mmbm: ArrayLike,
    policy: Union[str, Sequence[str]],
    exposure: float = _mmbm.DEFAULT_EXPOSURE_S,
    delay: float = _mmbm.DEFAULT_DELAY_S,
    readout: float = _mmbm.DEFAULT_READOUT_S,
    min_interval: float = _mmbm.DEFAULT_MIN_INTERVAL_S,
    pitch_mm: float = _mmbm.DEFAULT_PITCH_MM,
) -> List[Dict[str, Any]]:
    """Runs trigger policies (``fixed:5``, ``threshold:0.4``, ``oracle:0.4``,
    ...; see ``mmbm trigger --help``) on an MMBM series (``t`` s, ``mmbm``
    mm/s): one dict per frame with ``policy``, ``trigger_t``,
    ``exposure_start``, ``exposure_end`` (s), ``mmbm_trigger_mm_s``,
    ``mmbm_exposure_mm_s``, ``kept`` and ``gain``, as ``mmbm trigger``'s CSV rows.
    ``pitch_mm`` (the pixel pitch) turns MMBM into px for exposure control
    (``fixed:5+exp:2``: at most ~2 px of predicted blur per frame)."""
    policies = [policy] if isinstance(policy, str) else list(policy)
    tt = np.ascontiguousarray(np.asarray(t, dtype=np.float64).ravel())
    mm = np.ascontiguousarray(np.asarray(mmbm, dtype=np.float64).ravel())
    if tt.shape != mm.shape:
        raise ValueError(f"t has {tt.size} values, mmbm {mm.size}")
    return _mmbm.trigger(tt, mm, policies, float(exposure), float(delay), float(readout), float(min_interval), float(pitch_mm))


def read_exr(src: Union[PathLike, bytes]) -> Dict[str, np.ndarray]:
    """Reads a float EXR (mmbm's outputs) from a path or from the file's
    bytes (e.g. a WebDataset sample's ``exr`` field): ``{channel: (H, W) float32}``."""
    if isinstance(src, (bytes, bytearray, memoryview)):
        return _mmbm.read_exr(bytes(src))
    return _mmbm.read_exr(os.fspath(src))


def choose_frames(
    blur_px: ArrayLike,
    times_s: Optional[ArrayLike] = None,
    *,
    per_window: Optional[int] = None,
    per_seconds: Optional[float] = None,
    count: Optional[int] = None,
    select: Optional[int] = None,
    gap: float = 0.0,
    max_blur: Optional[float] = None,
) -> np.ndarray:
    """The chosen frames' indices (int64, in order) from each frame's blur,
    px (NaN: no value, never chosen), as ``mmbm frames`` chooses them:
    ``per_window=K`` the sharpest of every K frames, ``per_seconds=S`` of
    every S s of ``times_s``, ``count=N`` of N windows of equal frame counts
    (even coverage), ``select=N`` the N sharpest at least ``gap`` s apart;
    ``max_blur`` alone every frame at most that blur, with a mode its picks
    within it. ``times_s``: the frames' starts, s (default: the index)."""
    b = np.ascontiguousarray(np.asarray(blur_px, dtype=np.float64).ravel())
    t = None if times_s is None else np.ascontiguousarray(np.asarray(times_s, dtype=np.float64).ravel())
    if t is not None and t.shape != b.shape:
        raise ValueError(f"times_s has {t.size} values, blur_px {b.size}")
    def opt_int(x: Any, name: str) -> Optional[int]:
        if x is None:
            return None
        v = _int(x, name)
        if v < 0:
            raise ValueError(f"{name}: must be >= 0, got {v}")
        return v

    opt_f = lambda x: None if x is None else float(x)  # noqa: E731
    got = _mmbm.choose_frames(
        b, t, opt_int(per_window, "per_window"), opt_f(per_seconds), opt_int(count, "count"),
        opt_int(select, "select"), float(gap), opt_f(max_blur),
    )
    return np.asarray(got, dtype=np.int64)


_AUGMENT_DTYPES = (np.uint8, np.uint16, np.float32, np.float64)


def _motion_args(motion: Union[str, Dict[str, Any]]) -> Tuple[str, List[float], List[float], Optional[Dict[str, np.ndarray]]]:
    omega, velocity, gyro = [0.0] * 3, [0.0] * 3, None
    if isinstance(motion, str):
        return motion, omega, velocity, gyro
    if isinstance(motion, dict) and "t" in motion:
        gyro = {k: np.asarray(motion[k], dtype=np.float64) for k in ("t", "omega", "velocity") if k in motion}
        return "log", omega, velocity, gyro
    if isinstance(motion, dict) and "omega" in motion:
        omega = [float(v) for v in np.asarray(motion["omega"], dtype=np.float64).ravel()]
        velocity = [float(v) for v in np.asarray(motion.get("velocity", (0, 0, 0)), dtype=np.float64).ravel()]
        return "twist", omega, velocity, gyro
    raise ValueError("motion: 'shake', 'sim:GAIT', {'omega': ..., 'velocity': ...} or a read_gyro dict")


def _check_pixels(h: int, w: int) -> None:
    # From the shape alone, before any value is read or copied.
    if int(h) * int(w) > _mmbm.AUGMENT_MAX_PIXELS:
        raise ValueError(f"image: {w} x {h} px: at most {_mmbm.AUGMENT_MAX_PIXELS} px")


def _draw_seed() -> int:
    return int(np.random.SeedSequence().generate_state(1, np.uint64)[0] >> np.uint64(1))


def _sharp(sharp: Optional[str], centre: Optional[bool]) -> str:
    """``augment``'s ``sharp``, with ``centre`` (True: ``"mid"``, False:
    ``"start"``) as its alias; both given must agree."""
    alias = None if centre is None else ("mid" if centre else "start")
    if sharp is None:
        return alias or "mid"
    if sharp not in ("start", "mid", "end"):
        raise ValueError(f"sharp: 'start', 'mid' or 'end' expected, got {sharp!r}")
    if alias is not None and alias != sharp:
        raise ValueError(f"centre={centre} is sharp={alias!r}, which contradicts sharp={sharp!r}")
    return sharp


def _augment_nhwc(
    x: np.ndarray,
    seeds: List[int],
    p: float,
    motion: Union[str, Dict[str, Any]],
    exposure: float,
    camera: Optional[Camera],
    sharp: str,
    zoom: float,
    distance: float,
    at: Optional[float],
    srgb: Optional[bool],
    quality: str,
    background: Sequence[float],
    use_velocity: bool,
    integrator: str,
    border: str,
    blur_px: Optional[float],
    return_fields: bool,
    return_maps: bool = False,
    backend: str = "bulk",
) -> Dict[str, Any]:
    """The images of ``x`` ((N, H, W, C), any supported dtype, a view is
    fine), image ``k`` applied with probability ``p`` under ``seeds[k]``."""
    n, h, w, c = x.shape
    if not 0.0 <= float(p) <= 1.0:
        raise ValueError(f"p: {p}: expected 0 to 1")
    applied = [bool(np.random.default_rng([s, 0x70]).random() < p) for s in seeds]
    kind, omega, velocity, gyro = _motion_args(motion)
    dtype = x.dtype
    native = any(dtype == d for d in _AUGMENT_DTYPES)
    if not (native or np.issubdtype(dtype, np.floating)):
        raise ValueError(f"image: uint8, uint16 or float expected, got {dtype}")
    idx = [k for k in range(n) if applied[k]]
    out = {
        "image": np.array(x, copy=True) if idx else x,
        "homographies": np.tile(np.eye(3), (n, 3, 1, 1)),
        "motion": ["none"] * n,
        "seed": list(seeds),
        "applied": applied,
        "samples": [0] * n,
    }
    if return_maps:
        out["maps"] = {k: np.zeros((n, h, w), np.float32) for k in ("path_px", "disp_px", "speed_px_s")}
    if return_fields:
        out["fields"] = np.zeros((n, 3, h, w, 2), np.float32)
    if not idx:
        return out
    sub = x[idx] if len(idx) < n else x
    sub = np.ascontiguousarray(sub, dtype=dtype if native else np.float32)
    use_srgb = (dtype.kind == "u") if srgb is None else bool(srgb)
    img, maps, hs, fields, drawn, samples = _mmbm.augment(
        sub,
        [seeds[k] for k in idx],
        kind,
        omega,
        velocity,
        gyro,
        None if at is None else float(at),
        float(exposure),
        None if camera is None else camera._spec(),
        float(distance),
        float(zoom),
        sharp,
        quality,
        [float(v) for v in background],
        bool(use_velocity),
        use_srgb,
        integrator,
        border,
        None if blur_px is None else float(blur_px),
        bool(return_fields),
        bool(return_maps),
        str(backend),
    )
    out["image"][idx] = img.astype(dtype, copy=False)
    if return_maps:
        for key in out["maps"]:
            out["maps"][key][idx] = maps[key]
    out["homographies"][idx] = hs
    if return_fields:
        out["fields"][idx] = fields
    for j, k in enumerate(idx):
        out["motion"][k] = drawn[j]
        out["samples"][k] = samples[j]
    return out


def augment(
    image: ArrayLike,
    motion: Union[str, Dict[str, Any]] = "shake",
    exposure: float = 0.03,
    camera: Optional[Camera] = None,
    seed: Optional[int] = None,
    centre: Optional[bool] = None,
    zoom: float = 1.0,
    distance: float = 2.0,
    at: Optional[float] = None,
    srgb: Optional[bool] = None,
    quality: str = "default",
    background: Sequence[float] = (0.0, 0.0, 0.0),
    use_velocity: bool = True,
    *,
    p: float = 1.0,
    integrator: str = "fast",
    border: str = "reflect",
    blur_px: Optional[float] = None,
    return_fields: bool = False,
    sharp: Optional[str] = None,
    return_maps: bool = False,
    backend: str = "bulk",
) -> Dict[str, Any]:
    """Motion blur of ``image`` along a real or simulated camera motion.

    The image is a plane filling the view (``zoom`` times the view's width)
    ``distance`` m away; the camera moves during ``exposure`` s:
    ``motion="shake"`` (a walk of a gait drawn from ``seed``, from a start
    drawn from ``seed``), ``"sim:slow"``, ``"sim:moderate"``, ``"sim:fast"``
    (a simulated walk), ``{"omega": [wx, wy, wz], "velocity": [vx, vy, vz]}``
    (a constant twist, rad/s and m/s, camera frame) or a ``read_gyro`` dict
    with ``at`` (a window of a real log starting at ``at`` s). ``sharp``:
    the instant at which ``image`` is the sharp frame (the reference pose):
    ``"mid"`` (default: no net shift, the blur spreads around each point, as
    GoPro / REDS pair a blurred frame with its middle sharp frame and as
    ``mmbm dataset`` does), ``"start"`` or ``"end"``; ``centre=True`` is ``sharp="mid"`` (``False``:
    ``"start"``).
    ``camera``: default the thesis focal length and pitch at the image's
    size (a given camera must have that size; lens distortion is refused).

    ``seed``: None (default) draws one from OS entropy (returned as
    ``"seed"``); a given seed reproduces the call. ``p``: the probability
    of applying (drawn from the seed); when not applied the input itself is
    returned. ``blur_px``: the motion scaled so that the mean path over the
    frame (the mean of ``return_maps``' ``path_px``) is that many px. ``border``:
    ``"reflect"`` (mirrored about the edge pixels, OpenCV's REFLECT_101),
    ``"replicate"`` or ``"constant"`` (``background``, linear RGB;
    transparent with alpha). ``integrator``: ``"fast"`` (warp samples at
    most 1 px apart at the peak speed, at least 8: within 0.5/255 mean,
    3/255 p99 of the exact time integral; 2 px apart would not be),
    ``"exact"`` (1/32 px apart) or ``"render"`` (the renderer's pixel-area
    integral, ``quality``; border ``"constant"`` only).
    ``backend``: where ``fast`` and ``exact`` run: ``"bulk"`` (default: a
    hardware GPU, else the CPU; a software adapter such as Mesa lavapipe is
    slower than the CPU), ``"auto"`` (any GPU adapter, else the CPU),
    ``"gpu"`` (an adapter or an error) or ``"cpu"``; the GPU kernel computes
    the same formula in f32 (within 1e-4 of the CPU's linear values).
    Without motion the input comes back bit for bit.

    ``image``: (H, W) or (H, W, C) with C 1, 3 or 4 (straight alpha, blurred
    with the colour premultiplied); uint8 or uint16 (sRGB, ``srgb`` default
    True) or float (linear, ``srgb`` ignored). Returns ``{"image"`` (same
    shape and dtype), ``"homographies"`` ((3, 3, 3) float64: image pixel
    coordinates to the blurred frame's at exposure start, middle and end;
    (0, 0) the top-left corner), ``"motion"`` (what was drawn, e.g.
    ``sim:moderate@2.7141s``; ``"none"`` when not applied), ``"seed"``,
    ``"applied"``, ``"samples"`` (warp instants; 0: returned as given) and
    with ``return_fields`` ``"fields"`` ((3, H, W, 2) float32: for each
    pixel the displacement (x, y) px to the image point it sees at its
    exposure's start, middle and end), with ``return_maps`` ``"maps"``
    (``path_px``, ``disp_px``, ``speed_px_s``, (H, W) float32: computed only
    when asked, as they cost more than the fast blur)``}``.

    >>> out = augment(np.zeros((24, 32, 3), np.uint8), motion="sim:fast", exposure=0.02)
    >>> out["image"].shape, out["homographies"].shape
    ((24, 32, 3), (3, 3, 3))
    """
    a = np.asarray(image)
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (1, 3, 4)):
        raise ValueError(f"image: (H, W) or (H, W, C) with C 1, 3 or 4 expected, got shape {a.shape}")
    _check_pixels(a.shape[0], a.shape[1])
    x = a[None, :, :, None] if a.ndim == 2 else a[None]
    s = _draw_seed() if seed is None else int(seed)
    out = _augment_nhwc(
        x, [s], p, motion, exposure, camera, _sharp(sharp, centre), zoom, distance, at, srgb, quality, background,
        use_velocity, integrator, border, blur_px, return_fields, return_maps, backend,
    )
    res = {
        "image": a if not out["applied"][0] else out["image"][0].reshape(a.shape),
        "homographies": out["homographies"][0],
        "motion": out["motion"][0],
        "seed": s,
        "applied": out["applied"][0],
        "samples": out["samples"][0],
    }
    if return_fields:
        res["fields"] = out["fields"][0]
    if return_maps:
        res["maps"] = {k: v[0] for k, v in out["maps"].items()}
    return res


def augment_batch(
    images: ArrayLike,
    seeds: Optional[Sequence[int]] = None,
    layout: Optional[str] = None,
    **kwargs: Any,
) -> Dict[str, Any]:
    """``augment`` over a batch, in parallel (one task per image, the GIL
    released), each image with its own seed and so its own motion: ``seeds``,
    else ``seed + k`` for image ``k`` when ``seed`` is given, else each drawn
    from OS entropy. ``images``: an array (N, H, W) (gray), (N, H, W, C)
    (``layout="NHWC"``) or (N, C, H, W) (``layout="NCHW"``), C 1, 3 or 4;
    without ``layout`` the last axis of size 1, 3 or 4 is taken as the
    channels, else the second (NHWC when both are), or a list of images.
    Returns ``augment``'s keys with a leading batch axis (the images in the
    input's layout and dtype; ``"motion"``, ``"seed"``, ``"applied"`` and
    ``"samples"`` lists); a list of images of different shapes gives lists."""
    base = kwargs.pop("seed", None)
    if isinstance(images, (list, tuple)):
        shapes = {np.shape(im) for im in images}
        if len(shapes) > 1:
            seeds = _batch_seeds(len(images), seeds, base)
            outs = [augment(im, seed=s, **kwargs) for im, s in zip(images, seeds)]
            return {k: [o[k] for o in outs] for k in outs[0]} if outs else {}
        images = np.stack([np.asarray(im) for im in images]) if images else np.zeros((0, 2, 2, 3), np.float32)
    a = np.asarray(images)
    if a.ndim == 3:
        lay = "NHW"
    elif a.ndim == 4:
        lay = layout
        if lay is None:
            lay = "NHWC" if a.shape[3] in (1, 3, 4) else "NCHW" if a.shape[1] in (1, 3, 4) else None
        if lay not in ("NHWC", "NCHW"):
            raise ValueError(f"layout: {layout!r} for shape {a.shape}: give 'NHWC' or 'NCHW' (channels 1, 3 or 4)")
    else:
        raise ValueError(f"images: (N, H, W), (N, H, W, C) or (N, C, H, W) expected, got shape {a.shape}")
    h, w = (a.shape[2], a.shape[3]) if lay == "NCHW" else (a.shape[1], a.shape[2])
    _check_pixels(h, w)
    x = a[..., None] if lay == "NHW" else np.moveaxis(a, 1, -1) if lay == "NCHW" else a
    if x.shape[3] not in (1, 3, 4):
        raise ValueError(f"images: {x.shape[3]} channels: expected 1, 3 or 4")
    seeds = _batch_seeds(a.shape[0], seeds, base)
    defaults = dict(
        motion="shake", exposure=0.03, camera=None, centre=None, sharp=None, zoom=1.0, distance=2.0, at=None, srgb=None,
        quality="default", background=(0.0, 0.0, 0.0), use_velocity=True, integrator="fast", border="reflect",
        blur_px=None, return_fields=False, return_maps=False, backend="bulk",
    )
    p = kwargs.pop("p", 1.0)
    unknown = set(kwargs) - set(defaults)
    if unknown:
        raise TypeError(f"augment_batch: unknown arguments {sorted(unknown)}")
    defaults.update(kwargs)
    defaults["sharp"] = _sharp(defaults.pop("sharp"), defaults.pop("centre"))
    out = _augment_nhwc(x, seeds, p, **defaults)
    img = out["image"]
    out["image"] = img[..., 0] if lay == "NHW" else np.moveaxis(img, -1, 1) if lay == "NCHW" else img
    return out


def _batch_seeds(n: int, seeds: Optional[Sequence[int]], base: Optional[int]) -> List[int]:
    if seeds is None:
        return [_draw_seed() for _ in range(n)] if base is None else [int(base) + k for k in range(n)]
    seeds = [int(s) for s in seeds]
    if len(seeds) != n:
        raise ValueError(f"seeds: {len(seeds)} for {n} images")
    return seeds


def __getattr__(name: str) -> Any:
    # ``mmbm.BlurDataset`` without importing torch at ``import mmbm``.
    if name == "BlurDataset":
        from .dataset import BlurDataset

        return BlurDataset
    raise AttributeError(f"module 'mmbm' has no attribute {name!r}")
