"""The cost of driving the renderer from Python: the wall time of
`Renderer.frame` against the frame time the renderer measures inside Rust
(`stats()["total_ms"]`), frame by frame in the same run.

    python examples/python/overhead.py --scene office --size 320x240
"""

import argparse
import time

import numpy as np

import vpl


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="office")
    ap.add_argument("--sampler", default="smc")
    ap.add_argument("--vpls", type=int, default=2048)
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--frames", type=int, default=12)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    r = vpl.Renderer(vpl.Scene.load(args.scene), sampler=args.sampler, vpls=args.vpls, size=(w, h))
    wall, inner = [], []
    for i in range(args.frames):
        t0 = time.perf_counter()
        r.frame(i)
        wall.append((time.perf_counter() - t0) * 1e3)
        inner.append(r.stats()["total_ms"])
    # The first two frames include the sampler's warm-up.
    wall, inner = np.array(wall[2:]), np.array(inner[2:])
    print(f"{args.sampler} on {args.scene} {w}x{h}, {args.vpls} VPLs, {len(wall)} frames:")
    print(f"  Renderer.frame from Python: median {np.median(wall):.1f} ms")
    print(f"  the frame inside Rust:      median {np.median(inner):.1f} ms")
    print(f"  overhead: median {100 * np.median(wall / inner - 1):.2f} %, worst {100 * np.max(wall / inner - 1):.2f} %")


if __name__ == "__main__":
    main()
