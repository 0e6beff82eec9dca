"""What ``follow_rig`` needs of your robot and camera.

Any objects with these methods will do (duck typing); subclassing is not
needed. The Rust servo loop calls them with the GIL held for the call and
blocks until they return.
"""

from typing import Protocol, Sequence, runtime_checkable

import numpy as np

Pose = Sequence[float]
"""(x, y, z, rx, ry, rz): mm and degrees, work frame; z is the height of the
sensor tip (the dome's lowest point) above the object's top face."""


@runtime_checkable
class Arm(Protocol):
    """A robot arm carrying the tactile sensor at its tool centre point."""

    def move_to(self, pose: Pose) -> None:
        """Move linearly to ``pose`` (mm, deg); block until reached.
        Raise an ``Exception`` to report a fault: the run stops safely."""

    def pose(self) -> Pose:
        """The commanded pose most recently reached (6 numbers, mm, deg)."""

    # Optional: tap_down(depth_mm) / tap_up(depth_mm), straight down / up
    # by depth_mm, blocking. Without them tactrace moves through move_to.


@runtime_checkable
class TactileSensor(Protocol):
    """A source of tactile frames (a camera in the TacTip)."""

    def capture(self) -> np.ndarray:
        """The current frame, a (H, W) grey image (uint8, white pins on
        black; other dtypes are converted); block until it is available."""
