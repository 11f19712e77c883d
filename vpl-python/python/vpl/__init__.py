"""Virtual-point-light global illumination from Python.

The VPL toolkit's scenes, path-traced reference, VPL samplers (Instant
Radiosity, Russian-roulette acceptance, Metropolis IR, TCAS, Sequential Monte
Carlo IR) and VPL renderer, with images and VPL sets as NumPy arrays, and VPL
samplers written in Python that plug into the same renderer.

>>> import vpl
>>> scene = vpl.Scene.load("cornell")
>>> image, stderr = vpl.render_path(scene, spp=16, size=(32, 32))
>>> image.shape
(32, 32, 3)
>>> r = vpl.Renderer(scene, sampler="smc", vpls=256, size=(32, 32))
>>> r.frame(0).shape
(32, 32, 3)

Every error of the toolkit is raised as :class:`VplError` with the toolkit's
one-line message. Long calls release the GIL and stop on Ctrl-C.
"""

from ._vpl import (
    FrameInfo,
    Renderer,
    Scene,
    VplError,
    __version__,
    compare,
    default_tracked_pixels,
    rel_mse,
    render_path,
    render_progressive,
    rmse,
    samplers,
    temporal_error,
    tone_mapped_luminance,
    track,
)
from ._experiments import compare_samplers, sequence

__all__ = [
    "FrameInfo",
    "Renderer",
    "Scene",
    "VplError",
    "__version__",
    "compare",
    "compare_samplers",
    "default_tracked_pixels",
    "rel_mse",
    "render_path",
    "render_progressive",
    "rmse",
    "samplers",
    "sequence",
    "temporal_error",
    "tone_mapped_luminance",
    "track",
]
