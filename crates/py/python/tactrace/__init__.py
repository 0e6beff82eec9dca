"""tactrace from Python: tactile contour following on numpy arrays.

The simulated TacTip, pin extraction, dendritic pose models and the servo
loop of the `tactrace` command, as Python objects. Lengths are millimetres,
angles degrees, image quantities pixels. Errors are ``TactraceError``;
bad input (what the CLI exits 2 for) is ``InputError``, also a
``ValueError``; a run that failed (exit 1) is ``RunFailedError``.

>>> import tactrace
>>> inputs, targets, meta = tactrace.load_dataset("data/sim_train")
>>> model = tactrace.load_model("models/pdennn")
>>> pose = model.predict(inputs)             # (N, 2): r mm, theta deg
>>> tip = tactrace.SimTacTip()
>>> frame = tip.render(r_mm=1.0, theta_deg=10.0)   # uint8 (256, 256)
>>> pins = tactrace.PinExtractor(tip.render_rest(), preset="sim")
>>> pins.displacement(frame).shape
(254,)
>>> run = tactrace.follow(model, "flower")
>>> run["closed"], run["mean_l2_mm"]
"""

from ._tactrace import (
    InputError,
    Model,
    PinExtractor,
    RunFailedError,
    SimTacTip,
    TactraceError,
    __version__,
    follow,
    follow_rig,
    load_dataset,
    load_model,
    read_frame,
    save_dataset,
    train,
)
from .protocols import Arm, TactileSensor

__all__ = [
    "Arm",
    "InputError",
    "Model",
    "PinExtractor",
    "RunFailedError",
    "SimTacTip",
    "TactileSensor",
    "TactraceError",
    "__version__",
    "follow",
    "follow_rig",
    "load_dataset",
    "load_model",
    "read_frame",
    "save_dataset",
    "train",
]
