"""Type stubs of the extension module (see the docstrings for units)."""

from os import PathLike
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

StrPath = Union[str, PathLike]
ArrayLike = npt.ArrayLike
Shape = Union[str, PathLike, npt.ArrayLike]
Config = Union[StrPath, dict]

__version__: str

class TactraceError(Exception): ...
class RunFailedError(TactraceError): ...
class InputError(TactraceError, ValueError): ...

def load_dataset(
    dir: StrPath,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32], dict]: ...
def save_dataset(
    dir: StrPath,
    inputs: ArrayLike,
    targets: ArrayLike,
    meta: dict,
    *,
    force: bool = False,
) -> str: ...

def import_dataset(
    frames: StrPath,
    labels: StrPath,
    out: StrPath,
    *,
    target: Sequence[str] = (),
    image_column: Optional[str] = None,
    r_column: Optional[str] = None,
    theta_column: Optional[str] = None,
    sensor: Optional[StrPath] = None,
    reference: Optional[StrPath] = None,
    params: Optional[StrPath] = None,
    like: Optional[StrPath] = None,
    limit: Optional[int] = None,
    force: bool = False,
) -> Dict[str, Any]: ...

Samples = Union[StrPath, Tuple[ArrayLike, ArrayLike, dict], ArrayLike]
"""A dataset folder, the (inputs, targets, meta) of load_dataset, or an
N x 2P array of inputs (then reference_pins is required)."""

class Model:
    @property
    def reference_pins(self) -> npt.NDArray[np.float64]: ...
    @property
    def config(self) -> dict: ...
    @property
    def kind(self) -> str: ...
    @property
    def input_dim(self) -> int: ...
    @property
    def history(self) -> list: ...
    @property
    def validation(self) -> Optional[dict]: ...
    @property
    def training(self) -> Optional[dict]: ...
    @property
    def targets(self) -> List[Dict[str, Any]]: ...
    def predict(
        self,
        data: Samples,
        *,
        reference_pins: Optional[ArrayLike] = None,
        views: Optional[bool] = None,
    ) -> npt.NDArray[np.float64]: ...
    @overload
    def predict_targets(
        self,
        data: Samples,
        *,
        reference_pins: Optional[ArrayLike] = None,
        named: Literal[False] = False,
    ) -> npt.NDArray[np.float64]: ...
    @overload
    def predict_targets(
        self,
        data: Samples,
        *,
        reference_pins: Optional[ArrayLike] = None,
        named: Literal[True],
    ) -> Dict[str, Any]: ...
    def validate(
        self,
        data: Samples,
        targets: Optional[ArrayLike] = None,
        *,
        reference_pins: Optional[ArrayLike] = None,
        views: Optional[bool] = None,
    ) -> dict: ...
    def save(self, dir: StrPath, *, force: bool = False) -> str: ...

class ImageModel:
    """An image model (conv-dennn, conv-mlp): grey frames in, N targets out."""
    @property
    def targets(self) -> list: ...
    @property
    def kind(self) -> str: ...
    @property
    def input_size(self) -> Tuple[int, int]: ...
    @property
    def config(self) -> dict: ...
    @property
    def history(self) -> list: ...
    @property
    def training(self) -> Optional[dict]: ...
    def predict(
        self, frames: ArrayLike, *, views: Optional[bool] = None
    ) -> npt.NDArray[np.float64]: ...
    def validate(self, data: StrPath, *, views: Optional[bool] = None) -> dict: ...
    def save(self, dir: StrPath, *, force: bool = False) -> str: ...

def load_model(dir: StrPath) -> Union[Model, ImageModel]: ...
def train(
    kind: str,
    data: Union[Samples, List[StrPath]],
    targets: Optional[ArrayLike] = None,
    reference_pins: Optional[ArrayLike] = None,
    *,
    epochs: Optional[int] = None,
    seed: Optional[int] = None,
    preset: str = "default",
    config: Optional[Config] = None,
    val_fraction: Optional[float] = None,
    split_seed: int = 1,
) -> Union[Model, ImageModel]: ...
def read_frame(path: StrPath) -> npt.NDArray[np.uint8]: ...

class PinExtractor:
    def __init__(
        self,
        reference_frame: Union[ArrayLike, StrPath],
        *,
        preset: str = "real256",
        params: Optional[StrPath] = None,
    ) -> None: ...
    @property
    def reference_pins(self) -> npt.NDArray[np.float64]: ...
    def extract(self, frame: Union[ArrayLike, StrPath]) -> npt.NDArray[np.float64]: ...
    def displacement(
        self, frame: Union[ArrayLike, StrPath]
    ) -> npt.NDArray[np.float32]: ...

Image = Union[ArrayLike, StrPath]
"""A camera image: (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA, or an image file."""

def preprocess(frame: Image, sensor: Union[StrPath, dict]) -> npt.NDArray[np.uint8]: ...
def inspect_sensor(
    frames: Union[StrPath, Sequence[StrPath]],
    *,
    crop: Optional[Tuple[int, int, int, int]] = None,
    out: Optional[StrPath] = None,
    picture: Optional[StrPath] = None,
    force: bool = False,
) -> Dict[str, Any]: ...

class PinReader:
    def __init__(self, sensor: Union[StrPath, dict], reference_pins: ArrayLike) -> None: ...
    @property
    def reference_pins(self) -> npt.NDArray[np.float64]: ...
    def read(self, frame: Image) -> Tuple[npt.NDArray[np.float64], Dict[str, int]]: ...
    def displacement(self, frame: Image) -> npt.NDArray[np.float32]: ...

class SimTacTip:
    def __init__(
        self,
        sensor: Optional[StrPath] = None,
        seed: int = 0,
        *,
        shape: Optional[Shape] = None,
        config: Optional[StrPath] = None,
    ) -> None: ...
    def render(
        self,
        r_mm: float,
        theta_deg: float,
        depth_mm: Optional[float] = None,
        shear: Optional[Tuple[float, float, float]] = None,
        *,
        arc_mm: float = 0.0,
        noise: bool = False,
    ) -> npt.NDArray[np.uint8]: ...
    def render_rest(self) -> npt.NDArray[np.uint8]: ...
    def true_pins(
        self,
        r_mm: float,
        theta_deg: float,
        depth_mm: Optional[float] = None,
        shear: Optional[Tuple[float, float, float]] = None,
        *,
        arc_mm: float = 0.0,
    ) -> npt.NDArray[np.float64]: ...
    def render_at(self, pose: Sequence[float]) -> npt.NDArray[np.uint8]: ...
    @property
    def rest_pins(self) -> npt.NDArray[np.float64]: ...
    @property
    def shape(self) -> Tuple[int, int]: ...
    @property
    def calibrated(self) -> bool: ...

def follow(
    model: Union[Model, ImageModel, StrPath],
    shape: Shape,
    out: Optional[StrPath] = None,
    steps: Optional[int] = None,
    config: Optional[Config] = None,
    seed: Optional[int] = None,
    *,
    sensor: Optional[StrPath] = None,
    replay: Optional[Union[StrPath, dict]] = None,
    force: bool = False,
    check: bool = True,
) -> dict[str, Any]: ...
def follow_rig(
    model: Union[Model, ImageModel, StrPath],
    arm: Any,
    sensor: Any,
    *,
    config: Optional[Config] = None,
    shape: Optional[Shape] = None,
    out: Optional[StrPath] = None,
    steps: Optional[int] = None,
    seed: Optional[int] = None,
    force: bool = False,
    check: bool = True,
) -> dict[str, Any]: ...
def evaluate(name: str, context: str, config: str) -> str:
    """Run the named Rust evaluation, rebuilt from its JSON context, on one
    JSON configuration; the score as JSON (a remote executor's worker)."""
    ...

def prepare(name: str, context: str) -> bool:
    """Build the named Rust evaluation from its JSON context and keep it for
    the `evaluate` calls that follow; True when built now, False when kept
    from an earlier call in this process (a remote executor's worker)."""
    ...
