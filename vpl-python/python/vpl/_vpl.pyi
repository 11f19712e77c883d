"""Type stubs of the native module (re-exported by ``vpl``)."""

from typing import Any, Dict, List, Literal, Optional, Protocol, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

class VplError(Exception):
    """An error of the toolkit, with its one-line message."""

class Scene:
    """A scene at one frame of its animation."""

    @staticmethod
    def load(spec: str, allow_outside: List[str] = ...) -> "Scene": ...
    @staticmethod
    def builtins() -> List[str]: ...
    def at(self, frame: int) -> "Scene": ...
    @property
    def name(self) -> str: ...
    @property
    def frame(self) -> int: ...
    @property
    def frame_count(self) -> int: ...
    @property
    def fps(self) -> Optional[float]: ...
    @property
    def time(self) -> float: ...
    @property
    def triangles(self) -> int: ...
    @property
    def surface_area(self) -> float: ...
    @property
    def two_sided(self) -> bool: ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def lights(self) -> List[Dict[str, Any]]: ...
    @property
    def camera(self) -> Dict[str, Any]: ...
    @property
    def resolution(self) -> Tuple[int, int]: ...
    def sample_area(self, n: int, seed: int = 0) -> Dict[str, Any]: ...
    def radiosity(
        self, points: Dict[str, Any], paths: int = 16, max_bounces: int = 2, seed: int = 0
    ) -> npt.NDArray[np.float32]: ...

class FrameInfo:
    """What a Python sampler's ``next_frame`` receives."""

    @property
    def index(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def vpls(self) -> int: ...
    @property
    def scene(self) -> Optional[Scene]: ...

class PythonSampler(Protocol):
    """A VPL sampler written in Python."""

    def next_frame(
        self, frame: FrameInfo
    ) -> Union[
        Tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike],
        Tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike, npt.ArrayLike],
        Dict[str, npt.ArrayLike],
    ]: ...

class Renderer:
    """A VPL renderer over one scene, keeping its state from frame to frame."""

    def __init__(
        self,
        scene: Scene,
        sampler: Union[str, PythonSampler, None] = None,
        vpls: int = 2048,
        visibility: str = "shadowmap",
        shadow_map: int = 128,
        shading: str = "interleaved",
        filter: bool = True,
        backend: str = "cpu",
        mode: str = "full",
        max_depth: int = 5,
        clamp: Union[str, float, None] = None,
        compensation: int = 0,
        direct_samples: int = 16,
        seed: int = 0,
        size: Optional[Tuple[int, int]] = None,
        **params: Any,
    ) -> None: ...
    @overload
    def frame(self, index: int) -> npt.NDArray[np.float32]: ...
    @overload
    def frame(self, index: int, image: Literal[True]) -> npt.NDArray[np.float32]: ...
    @overload
    def frame(self, index: int, image: Literal[False]) -> None: ...
    def image(self) -> Optional[npt.NDArray[np.float32]]: ...
    def vpls(self) -> npt.NDArray[np.void]: ...
    def stats(self) -> Dict[str, Any]: ...
    def indirect(self) -> Optional[npt.NDArray[np.float32]]: ...
    @property
    def sampler(self) -> str: ...
    @property
    def backend(self) -> str: ...
    @property
    def device(self) -> Optional[str]: ...
    @property
    def vpls_budget(self) -> int: ...

def samplers() -> List[Dict[str, Any]]: ...
def render_path(
    scene: Scene,
    spp: int = 64,
    mode: str = "full",
    max_depth: int = 5,
    size: Optional[Tuple[int, int]] = None,
    seed: int = 0,
    materials: str = "as-is",
    progress: bool = False,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
def track(
    scene: Scene,
    pixels: List[Tuple[int, int]],
    spp: int = 4096,
    mode: str = "full",
    max_depth: int = 5,
    size: Optional[Tuple[int, int]] = None,
    seed: int = 0,
    footprint: str = "box",
    materials: str = "as-is",
    progress: bool = False,
    backend: str = "cpu",
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
def render_progressive(
    scene: Scene,
    passes: int = 64,
    size: Optional[Tuple[int, int]] = None,
    max_depth: int = 5,
    vpl_paths: int = 16,
    caustic_paths: int = 100000,
    gather: str = "exhaustive",
    seed: int = 0,
    progress: bool = False,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
def default_tracked_pixels(width: int, height: int) -> List[Tuple[int, int]]: ...
def rel_mse(a: npt.ArrayLike, b: npt.ArrayLike) -> float: ...
def rmse(a: npt.ArrayLike, b: npt.ArrayLike) -> float: ...
def temporal_error(estimate: npt.NDArray[np.float64], truth: npt.NDArray[np.float64]) -> Dict[str, float]: ...
def compare(
    a: npt.ArrayLike, a_se: npt.ArrayLike, b: npt.ArrayLike, b_se: npt.ArrayLike, alpha: float = 0.01
) -> Dict[str, Any]: ...
def tone_mapped_luminance(rgb: npt.ArrayLike) -> npt.NDArray[np.float64]: ...
