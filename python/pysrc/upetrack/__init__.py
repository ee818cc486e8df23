"""UPETrack: track a rope, cable or thread in RGB-D frames.

The tracker steps on numpy arrays as pyrealsense2 gives them (uint8 H x W x 3
RGB, uint16 H x W depth aligned to colour); `open` reads what the `upetrack`
command reads (sequence folders, .zip, .bag, .db3, .mcap) and `track` runs a
whole sequence as `upetrack track` does. Everything is the Rust core's.
"""

from . import _upetrack
from ._upetrack import *  # noqa: F401,F403 (the extension's names, listed once in its __all__)

__all__ = _upetrack.__all__
