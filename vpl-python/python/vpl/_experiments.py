"""Sequences and small Table 1 runs on top of the renderer.

Pure Python over :class:`vpl.Renderer` and :func:`vpl.track`: every frame is
one ``Renderer.frame`` call, so a sampler written in Python takes part the
same way a built-in does.
"""

from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from ._vpl import Renderer, Scene, VplError, default_tracked_pixels, temporal_error, tone_mapped_luminance, track


def _bar(items: List[Any], show: bool, desc: str) -> Iterable[Any]:
    """``items`` under a tqdm bar when ``show`` and tqdm is installed."""
    if show:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return items
        return tqdm(items, desc=desc)
    return items


def _frames(scene: Scene, frames: Optional[Iterable[int]]) -> List[int]:
    if frames is None:
        return list(range(scene.frame_count))
    out = list(frames)
    if not out:
        raise VplError("no frames to render")
    return out


def sequence(
    scene: Scene,
    frames: Optional[Iterable[int]] = None,
    tracked: Optional[Sequence[Tuple[int, int]]] = None,
    size: Optional[Tuple[int, int]] = None,
    renderer: Optional[Renderer] = None,
    images: bool = False,
    progress: bool = False,
    **settings: Any,
) -> Dict[str, Any]:
    """Renders frames of ``scene``'s animation with one renderer (built from
    ``settings``, the keywords of :class:`vpl.Renderer`, unless ``renderer``
    is given) and follows pixels over time.

    Returns a dict: ``frames`` (the indices), ``time`` (seconds), ``pixels``
    (the tracked (x, y), by default the SMC paper's eight), ``tracked``
    (float32 (frames, pixels, 3): their radiance), ``moved`` and
    ``total_ms`` per frame, ``stats`` (each frame's ``Renderer.stats()``),
    and ``images`` (float32 (frames, height, width, 3)) when asked for.
    ``progress=True`` shows a tqdm bar over the frames when tqdm is
    installed.
    """
    fr = _frames(scene, frames)
    w, h = size or scene.resolution
    r = renderer if renderer is not None else Renderer(scene, size=(w, h), **settings)
    pixels = list(tracked) if tracked is not None else default_tracked_pixels(w, h)
    for x, y in pixels:
        if not (0 <= x < w and 0 <= y < h):
            raise VplError(f"pixel ({x}, {y}) lies outside the {w}x{h} image")
    xs = np.array([p[0] for p in pixels], dtype=np.intp)
    ys = np.array([p[1] for p in pixels], dtype=np.intp)
    rows, stats, kept = [], [], []
    for f in _bar(fr, progress, "frames"):
        img = r.frame(f)
        rows.append(img[ys, xs])
        stats.append(r.stats())
        if images:
            kept.append(img)
    out: Dict[str, Any] = {
        "frames": np.array(fr),
        "time": np.array([scene.at(f).time if scene.frame_count > 1 else f / 30.0 for f in fr], dtype=np.float32),
        "pixels": pixels,
        "tracked": np.stack(rows).astype(np.float32),
        "moved": np.array([s["moved"] for s in stats]),
        "total_ms": np.array([s["total_ms"] for s in stats]),
        "stats": stats,
    }
    if images:
        out["images"] = np.stack(kept)
    return out


def compare_samplers(
    scene: Scene,
    samplers: Dict[str, Union[str, Any]],
    frames: Optional[Iterable[int]] = None,
    tracked: Optional[Sequence[Tuple[int, int]]] = None,
    size: Optional[Tuple[int, int]] = None,
    truth_spp: int = 4096,
    seeds: int = 1,
    progress: bool = False,
    **settings: Any,
) -> Dict[str, Any]:
    """A small Table 1: each sampler (a registry name, or a factory
    returning a fresh Python sampler per seed: a class or a function of no
    arguments) renders the frames in ``mode="indirect"`` with ``seeds``
    seeds; the tracked pixels' tone-mapped values are held against their
    path-traced truth per frame (``truth_spp`` paths through each pixel's
    centre, the point the renderer shades), as the SMC paper's |E| and
    |E′| (eq. 10).

    Returns a dict: ``pixels``, ``frames``, ``truth`` (frames, pixels),
    and ``rows``, one per sampler: ``e``, ``e_prime`` and ``bias`` (means
    over seeds) with their standard errors over seeds (``e_se``, ...; NaN
    for one seed), and ``values`` (seeds, frames, pixels).
    ``progress=True`` shows tqdm bars (the truth over frames, then each
    sampler over its runs) when tqdm is installed.
    """
    fr = _frames(scene, frames)
    w, h = size or scene.resolution
    pixels = list(tracked) if tracked is not None else default_tracked_pixels(w, h)
    settings = dict(settings)
    settings.setdefault("mode", "indirect")
    max_depth = settings.get("max_depth", 5)
    truth = np.stack(
        [
            tone_mapped_luminance(
                track(scene.at(f) if scene.frame_count > 1 else scene, pixels, spp=truth_spp, mode=settings["mode"], max_depth=max_depth, size=(w, h), seed=1_000_003 + f, footprint="centre", materials="diffuse")[0]
            )
            for f in _bar(fr, progress, "truth")
        ]
    )
    rows: Dict[str, Dict[str, Any]] = {}
    for name, sampler in samplers.items():
        per_seed, values = [], []
        for seed in _bar(list(range(seeds)), progress and seeds > 1, name):
            s = sampler if isinstance(sampler, str) else sampler()
            seq = sequence(scene, fr, pixels, (w, h), sampler=s, seed=seed, progress=progress and seeds == 1, **settings)
            v = tone_mapped_luminance(seq["tracked"])
            values.append(v)
            per_seed.append(temporal_error(v.astype(np.float64), truth))
        row: Dict[str, Any] = {"values": np.stack(values)}
        for k in ("e", "e_prime", "bias"):
            x = np.array([t[k] for t in per_seed])
            row[k] = float(x.mean())
            row[k + "_se"] = float(x.std(ddof=1) / np.sqrt(len(x))) if len(x) > 1 else float("nan")
        rows[name] = row
    return {"pixels": pixels, "frames": np.array(fr), "truth": truth, "rows": rows}
