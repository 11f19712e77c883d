"""Three VPL samplers on a short sequence, the SMC paper's Fig. 7 in small.

Renders frames of a scene's animation with Instant Radiosity, Metropolis IR
and SMC through the toolkit's renderer, follows a few pixels over time,
computes their path-traced truth per frame, and writes a Matplotlib figure of
the tone-mapped pixel values over time (one panel per pixel) with each
sampler's |E| and |E'|.

    python examples/python/compare_samplers.py --out fig7.png
"""

import argparse
import sys

import numpy as np

import vpl


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="office")
    ap.add_argument("--samplers", default="ir,mir,smc")
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--size", default="96x72", help="WIDTHxHEIGHT")
    ap.add_argument("--vpls", type=int, default=512)
    ap.add_argument("--truth-spp", type=int, default=8192)
    ap.add_argument("--out", default="fig7.png")
    args = ap.parse_args(argv)
    try:
        w, h = (int(v) for v in args.size.split("x"))
    except ValueError:
        print(f"compare_samplers: --size must be WIDTHxHEIGHT, not {args.size}", file=sys.stderr)
        return 2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = vpl.Scene.load(args.scene)
    frames = min(args.frames, scene.frame_count)
    # Four pixels spread over the image, away from its border.
    pixels = [(w // 4, h // 3), (3 * w // 4, h // 3), (w // 4, 2 * h // 3), (3 * w // 4, 2 * h // 3)]
    truth = np.array(
        [
            vpl.tone_mapped_luminance(vpl.track(scene.at(f), pixels, spp=args.truth_spp, mode="indirect", size=(w, h), seed=7, footprint="centre")[0])
            for f in range(frames)
        ]
    )
    series = {}
    for name in args.samplers.split(","):
        r = vpl.Renderer(scene, sampler=name, vpls=args.vpls, mode="indirect", size=(w, h), clamp="off", visibility="raytraced")
        values = []
        for f in range(frames):
            img = r.frame(f)
            values.append(vpl.tone_mapped_luminance(np.array([img[y, x] for x, y in pixels])))
        series[name] = np.array(values)
        e = vpl.temporal_error(series[name], truth)
        print(f"{name:>6}: |E| {e['e']:.4f}  |E'| {e['e_prime']:.4f}  bias {e['bias']:+.4f}  ({r.stats()['total_ms']:.0f} ms a frame)")
    fig, axes = plt.subplots(1, len(pixels), figsize=(4 * len(pixels), 3.2), sharey=False)
    t = np.arange(frames) / (scene.fps or 30.0)
    for p, ax in enumerate(axes):
        ax.plot(t, truth[:, p], "k-", lw=2, label="path traced")
        for name, v in series.items():
            ax.plot(t, v[:, p], lw=1, label=name)
        ax.set_title(f"pixel {pixels[p]}")
        ax.set_xlabel("time (s)")
    axes[0].set_ylabel("tone-mapped luminance")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{scene.name}: tracked pixels over time, {args.vpls} VPLs, indirect light")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
