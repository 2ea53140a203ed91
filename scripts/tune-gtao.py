#!/usr/bin/env python3
"""Tunes GTAO's free parameters (thickness, step spread, surface joining) against the
ray-traced reference over several scenes and radii, with `vrao bench`.

For every combination of the grid it benches `gtao` on every scene at three radii (the
scene's default radius × 0.5, 1, 2) and ranks the combinations by the mean over (scene,
radius) of RMSE + |bias| against the hard cut-off reference. It writes the full table
and the ranking as Markdown (default docs/records/2026-11-29/gtao-tuning.md) and prints the winner; the
winner goes into src/render/passes/gtao/mod.rs (GtaoSettings: its defaults).

usage: python3 scripts/tune-gtao.py [--vrao target/release/vrao] [--size 270x300]
       [--samples 24] [--scenes a,b,...] [--out docs/records/2026-11-29/gtao-tuning.md]
References are cached (~/.cache/vrao), so a second run only re-renders.
"""
import argparse
import csv
import itertools
import os
import subprocess
import sys
import tempfile
import time

SHARED = os.environ.get("VRAO_SCENES", os.path.join(os.path.dirname(__file__), "..", "..", "shared", "scenes"))
# The scene files name the public scenes as "$VRAO_SCENES/...": the binary needs the variable.
os.environ["VRAO_SCENES"] = os.path.abspath(SHARED)
DEFAULT_SCENES = [
    "builtin:crease",
    "builtin:furnished",
    "assets/scenes/cornell.toml",
    "assets/scenes/sibenik.toml",
    os.path.join(SHARED, "bunny", "bunny.obj"),
]
GRID = {
    "thickness": [0.1, 0.25, 0.5, 1.0],
    "step_power": [1.5, 2.0],
    "connect": [0.0, 0.25],
}


def bench(vrao, scene, size, samples, params, out):
    width, height = size.split("x")
    cmd = [vrao, "bench", "--scene", scene, "--techniques", "gtao", "--samples", str(samples),
           "--resolution", "full", "--frames", "1", "--warmup", "0", "--width", width, "--height", height,
           "--rays", "128", "--stride", "4", "--out", out,
           "--thickness", str(params["thickness"]), "--step-power", str(params["step_power"]),
           "--connect", str(params["connect"])]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "bench.csv")) as f:
        return list(csv.DictReader(f))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--vrao", default="target/release/vrao")
    ap.add_argument("--size", default="270x300")
    ap.add_argument("--samples", type=int, default=24)
    ap.add_argument("--scenes", default=",".join(DEFAULT_SCENES))
    ap.add_argument("--out", default="docs/records/2026-11-29/gtao-tuning.md")
    args = ap.parse_args()
    scenes = args.scenes.split(",")
    combos = [dict(zip(GRID, values)) for values in itertools.product(*GRID.values())]
    print(f"{len(combos)} combinations × {len(scenes)} scenes × 3 radii; the first pass traces references",
          file=sys.stderr)
    rows = []  # (combo index, scene, radius, rmse, bias, limit_rmse)
    started = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        for ci, params in enumerate(combos):
            for scene in scenes:
                for r in bench(args.vrao, scene, args.size, args.samples, params, tmp):
                    rows.append((ci, scene, float(r["radius_m"]), float(r["ao_rmse"]), float(r["ao_bias"]),
                                 float(r["limit_rmse"])))
            done = ci + 1
            eta = (time.time() - started) / done * (len(combos) - done)
            print(f"[{done}/{len(combos)}] {params}  ~{eta / 60:.0f} min left", file=sys.stderr)
    score = {}
    for ci in range(len(combos)):
        mine = [r for r in rows if r[0] == ci]
        score[ci] = (sum(r[3] + abs(r[4]) for r in mine) / len(mine),
                     sum(r[3] for r in mine) / len(mine), sum(r[4] for r in mine) / len(mine))
    ranking = sorted(score, key=lambda ci: score[ci][0])
    best = ranking[0]
    os.makedirs(os.path.dirname(args.out) or ".", exist_ok=True)
    with open(args.out, "w") as f:
        f.write("# GTAO tuning\n\n")
        f.write(f"`python3 scripts/tune-gtao.py --size {args.size} --samples {args.samples}`: gtao N = {args.samples} "
                f"at {args.size} per eye, both eyes, reference 128 rays at every 4th pixel, each scene at its "
                "default radius × 0.5, 1, 2. Score: mean over (scene, radius) of RMSE + |bias| against the hard "
                "cut-off reference.\n\n")
        f.write("| rank | thickness (× r) | step power | connect (× r) | score | mean RMSE | mean bias |\n|---|---|---|---|---|---|---|\n")
        for rank, ci in enumerate(ranking, 1):
            p = combos[ci]
            f.write(f"| {rank} | {p['thickness']} | {p['step_power']} | {p['connect']} | {score[ci][0]:.4f} | "
                    f"{score[ci][1]:.4f} | {score[ci][2]:+.4f} |\n")
        f.write("\nThe winner per scene and radius (RMSE, bias, and the screen-space limit's RMSE):\n\n")
        f.write("| scene | r (m) | RMSE | bias | limit RMSE |\n|---|---|---|---|---|\n")
        for r in rows:
            if r[0] == best:
                f.write(f"| {os.path.basename(r[1])} | {r[2]:.3g} | {r[3]:.3f} | {r[4]:+.3f} | {r[5]:.3f} |\n")
    print(f"best: {combos[best]} score {score[best][0]:.4f}; wrote {args.out}")


if __name__ == "__main__":
    main()
