"""tactrace from Python: tactile contour following on numpy arrays.

The simulated TacTip, pin extraction, dendritic pose models and the servo
loop of the `tactrace` command, as Python objects. Lengths are millimetres,
angles degrees, image quantities pixels. Errors are ``TactraceError``;
bad input (what the CLI exits 2 for) is ``InputError``, also a
``ValueError``; a run that failed (exit 1) is ``RunFailedError``.

A model is always given the pin order of its inputs: a dataset (a folder,
or what ``load_dataset`` returns) or arrays with ``reference_pins``.

>>> import tactrace
>>> inputs, targets, meta = tactrace.load_dataset("runs/reproduce/data/val")
>>> model = tactrace.load_model("runs/reproduce/models/pdennn")
>>> pose = model.predict(inputs, reference_pins=meta["reference_pins"])  # (N, 2)
>>> model.validate("runs/reproduce/data/val")["rows_seen_in_training"]
0
>>> tip = tactrace.SimTacTip()
>>> frame = tip.render(r_mm=1.0, theta_deg=10.0)   # uint8 (256, 256)
>>> pins = tactrace.PinExtractor(tip.render_rest(), preset="sim")
>>> pins.displacement(frame).shape
(254,)
>>> run = tactrace.follow(model, "flower")   # or sensor=FOLDER, replay=DIR
>>> run["closed"], run["mean_l2_mm"]

Any TacTip's raw frames: ``inspect_sensor`` proposes a sensor file,
``preprocess`` and ``PinReader`` read frames through it, and
``import_dataset`` imports a collection with named targets, as the CLI.
"""

from ._tactrace import (
    ImageModel,
    InputError,
    Model,
    PinExtractor,
    PinReader,
    RunFailedError,
    SimTacTip,
    TactraceError,
    __version__,
    follow,
    follow_rig,
    import_dataset,
    inspect_sensor,
    load_dataset,
    load_model,
    preprocess,
    read_frame,
    save_dataset,
    train,
)
from .protocols import Arm, TactileSensor

__all__ = [
    "Arm",
    "ImageModel",
    "InputError",
    "Model",
    "PinExtractor",
    "PinReader",
    "RunFailedError",
    "SimTacTip",
    "TactileSensor",
    "TactraceError",
    "__version__",
    "follow",
    "follow_rig",
    "import_dataset",
    "inspect_sensor",
    "load_dataset",
    "load_model",
    "preprocess",
    "read_frame",
    "save_dataset",
    "train",
]
