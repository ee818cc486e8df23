"""Type stubs of the extension module (the Rust core's bindings)."""

from os import PathLike
from typing import Mapping, Optional, Sequence as Seq, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Hsv = Tuple[Tuple[int, int, int], Tuple[int, int, int]]
Rect = Tuple[int, int, int, int]
Params = Union[None, str, Mapping[str, object]]
Path = Union[str, "PathLike[str]"]

class TrackerError(ValueError):
    """The tracker refused its settings or a frame (the core's message)."""

class SequenceError(ValueError):
    """A sequence or recording that cannot be read (naming the file)."""

class Intrinsics:
    """A pinhole camera: image size, focal lengths and principal point in pixels."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    def __init__(self, width: int, height: int, fx: float, fy: float, cx: float, cy: float) -> None: ...
    @staticmethod
    def from_realsense(intrinsics: object) -> "Intrinsics":
        """From pyrealsense2's `rs.intrinsics` (width, height, fx, fy, ppx, ppy)."""

class StepResult:
    """One step: nodes (M x 3 float64, metres, camera frame), visibility, loss, times (ms)."""

    nodes: npt.NDArray[np.float64]
    visible: npt.NDArray[np.bool_]
    lost: bool
    reason: Optional[str]
    recovered: bool
    segment_ms: float
    cloud_ms: float
    track_ms: float
    total_ms: float

class Tracker:
    """Tracks one rope in aligned colour and depth frames of one camera."""

    def __init__(
        self,
        intrinsics: Intrinsics,
        params: Params = None,
        algorithm: Optional[str] = None,
        depth_scale: float = 0.001,
        hsv: Optional[Hsv] = None,
        occlusions: Seq[Rect] = (),
    ) -> None: ...
    def step(
        self,
        color: npt.NDArray[np.uint8],
        depth: npt.NDArray[np.uint16],
        occlusions: Optional[Seq[Rect]] = None,
    ) -> StepResult:
        """Track one frame: color uint8 H x W x 3 RGB, depth uint16 H x W, aligned to colour."""
    def reset(self) -> None:
        """Forget the rope: the next frame finds it again."""

Arrays = Tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint16]]

class Frames:
    """The frames of a sequence in order, as (time in seconds, (color, depth))."""

    def __iter__(self) -> "Frames": ...
    def __next__(self) -> Tuple[float, Arrays]: ...

class Sequence:
    """A sequence folder, .zip or recording, opened as the command opens it."""

    intrinsics: Intrinsics
    depth_scale: float
    fps: float
    hsv: Hsv
    def __len__(self) -> int: ...
    def __getitem__(self, index: int) -> Arrays: ...
    def time(self, index: int) -> float:
        """Seconds: a recording's own colour time from its first message; a folder's frames at its rate from 0."""
    def frames(self) -> Frames:
        """Every frame in order as (time, (color, depth))."""
    def occlusions_at(self, index: int) -> list[Rect]: ...
    def tracker(self, params: Params = None, algorithm: Optional[str] = None) -> Tracker: ...

def open(path: Path, dlo: Optional[Path] = None) -> Sequence:
    """Open a sequence folder, a .zip, or a recording (.bag, .db3, .mcap; dlo: its dlo.json)."""

def track(
    path: Path,
    out: Optional[Path] = None,
    params: Params = None,
    algorithm: Optional[str] = None,
    dlo: Optional[Path] = None,
) -> str:
    """Track every frame as `upetrack track` does; the result JSON's text (also written to out)."""

def algorithms() -> list[str]:
    """The tracking algorithms' names."""
