"""Type stubs of the extension module (the Rust core's bindings)."""

from os import PathLike
from typing import Mapping, Optional, Sequence as Seq, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "Frames",
    "Intrinsics",
    "MultiTracker",
    "Sequence",
    "SequenceError",
    "StepResult",
    "Tracker",
    "TrackerError",
    "__version__",
    "algorithms",
    "open",
    "track",
]

_Hsv = Tuple[Tuple[int, int, int], Tuple[int, int, int]]
_Rect = Tuple[int, int, int, int]
_Params = Union[None, str, Mapping[str, object]]
_Path = Union[str, "PathLike[str]"]
_Arrays = Tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint16]]

class TrackerError(ValueError):
    """The tracker refused its settings or a frame (the core's message)."""

class SequenceError(ValueError):
    """A sequence or recording that cannot be read (naming the file)."""

@final
class Intrinsics:
    """A pinhole camera: image size, focal lengths and principal point in pixels."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    def __new__(cls, width: int, height: int, fx: float, fy: float, cx: float, cy: float) -> "Intrinsics": ...
    @staticmethod
    def from_realsense(intrinsics: object) -> "Intrinsics":
        """From pyrealsense2's `rs.intrinsics` (width, height, fx, fy, ppx, ppy)."""

@final
class StepResult:
    """One step: nodes (M x 3 float64, metres, camera frame), visibility, loss or recovery and why (`reason`), what came of the recovery tests (`verdict`, the tests that `fired`), times (ms)."""

    nodes: npt.NDArray[np.float64]
    visible: npt.NDArray[np.bool_]
    lost: bool
    reason: Optional[str]
    recovered: bool
    verdict: Optional[str]
    """"agreed", "waited", "nothing_found", "other_thickness", "beside_the_rope", "leaves_seen_rope_out" or "recovered"; None when no step ran (initialised or lost)."""
    fired: list[str]
    """The recovery tests that fired after the step: "stretched", "free_space", "unexplained"."""
    segment_ms: float
    cloud_ms: float
    track_ms: float
    total_ms: float

@final
class Tracker:
    """Tracks one rope in aligned colour and depth frames of one camera."""

    def __new__(
        cls,
        intrinsics: Intrinsics,
        params: _Params = None,
        algorithm: Optional[str] = None,
        depth_scale: float = 0.001,
        hsv: Optional[_Hsv] = None,
        occlusions: Seq[_Rect] = ...,
        chroma_noise: int = 0,
        fps: float = 30.0,
    ) -> "Tracker": ...
    def step(
        self,
        color: npt.NDArray[np.uint8],
        depth: npt.NDArray[np.uint16],
        occlusions: Optional[Seq[_Rect]] = None,
    ) -> StepResult:
        """Track one frame: color uint8 H x W x 3 RGB, depth uint16 H x W, aligned to colour."""
    def move_camera(self, motion: npt.NDArray[np.float64]) -> None:
        """The camera moved since the last frame: a 4 x 4 or 3 x 4 rigid transform
        from the last frame's camera coordinates to this frame's (metres)."""
    def reset(self) -> None:
        """Forget the rope: the next frame finds it again."""

@final
class MultiTracker:
    """Tracks every rope of a sequence of several together, as `upetrack track` does."""

    @property
    def ropes(self) -> list[str]:
        """The ropes' names, in the order of `step`'s results."""
    def step(
        self,
        color: npt.NDArray[np.uint8],
        depth: npt.NDArray[np.uint16],
        occlusions: Seq[_Rect] = ...,
    ) -> list[StepResult]:
        """Track one frame: one result per rope, in order (the times are the whole frame's)."""
    def move_camera(self, motion: npt.NDArray[np.float64]) -> None:
        """The camera moved since the last frame (as `Tracker.move_camera`): every rope moves with it."""
    def reset(self) -> None:
        """Forget every rope: the next frame finds them again."""

@final
class Frames:
    """The frames of a sequence in order, as (time in seconds, (color, depth))."""

    def __iter__(self) -> "Frames": ...
    def __next__(self) -> Tuple[float, _Arrays]: ...

@final
class Sequence:
    """A sequence folder, .zip or recording, opened as the command opens it."""

    intrinsics: Intrinsics
    depth_scale: float
    fps: float
    hsv: _Hsv
    chroma_noise: int
    def __len__(self) -> int: ...
    def __getitem__(self, index: int, /) -> _Arrays: ...
    def time(self, index: int) -> float:
        """Seconds: a recording's own colour time from its first message; a folder's frames at its rate from 0."""
    def frames(self) -> Frames:
        """Every frame in order as (time, (color, depth))."""
    def occlusions_at(self, index: int) -> list[_Rect]:
        """The occluder rectangles (x, y, w, h) dlo.json declares on frame `index`: pass them to
        `Tracker.step(..., occlusions=...)` for that frame (a tracker does not know which frame it is given)."""
    @property
    def ropes(self) -> list[str]:
        """The names of the ropes dlo.json lists (one name for one rope)."""
    def tracker(self, params: _Params = None, algorithm: Optional[str] = None, rope: int = 0) -> Tracker:
        """A tracker of this sequence's rope (with several ropes, rope `rope` alone; `track` tracks them together).
        Its `step` applies the rectangles it is given: `occlusions=seq.occlusions_at(i)` for frame i."""
    def multi_tracker(self, params: _Params = None, algorithm: Optional[str] = None) -> MultiTracker:
        """A tracker of every rope dlo.json lists, together, as `upetrack track` tracks them."""

def open(path: _Path, dlo: Optional[_Path] = None) -> Sequence:
    """Open a sequence folder, a .zip, or a recording (.bag, .db3, .mcap; dlo: its dlo.json)."""

def track(
    path: _Path,
    out: Optional[_Path] = None,
    params: _Params = None,
    algorithm: Optional[str] = None,
    dlo: Optional[_Path] = None,
) -> str:
    """Track every frame as `upetrack track` does; the result JSON's text (also written to out)."""

def algorithms() -> list[str]:
    """The tracking algorithms' names."""
