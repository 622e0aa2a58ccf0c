# Type stubs of the native module (python/src/lib.rs). The public API, with
# docstrings and units, is mmbm/__init__.py.
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

# A camera: the keys of a camera file (focal_mm, pitch_x_mm, ..., distortion, noise, lens).
CamSpec = Dict[str, Any]
F64 = npt.NDArray[np.float64]
F32 = npt.NDArray[np.float32]

def camera_from_file(path: str) -> str: ...
def camera_thesis() -> str: ...
def camera_check(cam: CamSpec) -> None: ...
def metric(cam: CamSpec, omega: F64, velocity: F64, plane_: Optional[F64], method: str) -> F64: ...
def series(
    cam: CamSpec,
    t: F64,
    omega: F64,
    velocity: Optional[F64],
    depth: Optional[F64],
    plane_: Optional[F64],
    method: str,
) -> F64: ...
def frames(
    cam: CamSpec, t: F64, omega: F64, t_start: F64, exposure_s: F64, readout_s: Optional[F64], method: str
) -> Tuple[F64, F64, F64]: ...
def frame_maps(
    cam: CamSpec, t: F64, omega: F64, t_start: F64, exposure_s: F64, readout_s: Optional[F64]
) -> List[Optional[npt.NDArray[np.float32]]]: ...
def read_gyro(
    path: str,
    time_unit: str,
    angle_unit: str,
    imu_rotation: Optional[str],
    time_offset: float,
    topic: Optional[str],
) -> Dict[str, F64]: ...
def read_camera(
    path: str,
    time_unit: str,
    angle_unit: str,
    imu_rotation: Optional[str],
    time_offset: float,
    topic: Optional[str],
    orientation: Optional[str],
) -> Dict[str, Any]: ...
def flow_field(
    cam: CamSpec, omega: Sequence[float], velocity: Sequence[float], plane_: Optional[F64], backend_: str
) -> F32: ...
def render(
    cam: CamSpec,
    target: str,
    distance: float,
    tilt: Sequence[float],
    offset: Sequence[float],
    background: Optional[Sequence[float]],
    exposure: float,
    omega: Optional[Sequence[float]],
    velocity: Sequence[float],
    gyro: Optional[Dict[str, F64]],
    at: Optional[float],
    use_velocity: bool,
    quality: str,
    integrator: str,
    backend_: str,
    seed: int,
    maps: bool,
    sharp: bool,
) -> Tuple[F32, Optional[Dict[str, F32]]]: ...
def simulate(gait: str, duration: float, rate: float, seed: int, config: Optional[str]) -> Dict[str, F64]: ...
def trigger(
    t: F64, mmbm_mm_s: F64, policies: List[str], exposure: float, delay: float, readout: float, min_interval: float, pitch_mm: float
) -> List[Dict[str, Any]]: ...
def read_exr(src: Union[str, bytes]) -> Dict[str, F32]: ...
def choose_frames(
    blur_px: F64,
    times_s: Optional[F64] = ...,
    per_window: Optional[int] = ...,
    per_seconds: Optional[float] = ...,
    count: Optional[int] = ...,
    select: Optional[int] = ...,
    gap: float = ...,
    max_blur: Optional[float] = ...,
) -> List[int]: ...

class DatasetMaker:
    def __init__(self, path: Optional[str] = ..., toml: Optional[str] = ...) -> None: ...
    @property
    def count(self) -> int: ...
    @property
    def fingerprint(self) -> str: ...
    def make(self, index: int, dir: str) -> str: ...
def augment(
    images: Any,
    seeds: List[int],
    motion: str,
    omega: Sequence[float],
    velocity: Sequence[float],
    gyro: Optional[Dict[str, F64]],
    at: Optional[float],
    exposure: float,
    cam: Optional[Dict[str, Any]],
    distance: float,
    zoom: float,
    sharp: str,
    quality: str,
    background: Sequence[float],
    use_velocity: bool,
    srgb: bool,
    integrator: str,
    border: str,
    blur_px: Optional[float],
    fields: bool,
    maps: bool,
    backend: str = "bulk",
) -> Tuple[Any, Optional[Dict[str, F32]], F64, Optional[F32], List[str], List[int]]: ...

AUGMENT_MAX_PIXELS: int
