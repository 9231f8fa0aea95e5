#!/usr/bin/env python3
"""Adaptive sampling against uniform sampling, to the same target error.

For each scene, sluice-raytrace --mode path renders to each --target-error
twice, with adaptive sampling (the default: 8x8 tiles stop once their own
estimate reaches the target) and with --no-adaptive (every pixel takes every
sample), at the reference's size, light samples and depth. Each render's
true relMSE is measured against the converged reference (bench/references.py,
rendered when missing), beside the estimate the render made of itself, its
time and the pixel samples it took.

  bench/bench_adaptive.py [--scenes cornell glassball] [--targets 0.03 0.01]
                          [--build build] [--out bench/results/adaptive.json]

Writes JSON naming the CPU and the load average at the start, and prints a
table. Times are single runs; on a shared machine the pixel-sample counts
(deterministic for a seed) are the steadier figure."""
import argparse
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import references  # noqa: E402  (bench/references.py: sizes, cpu_model)


def relmse(build, img, ref):
    out = subprocess.run([os.path.join(build, "apps/common/sluice-imgdiff"), img, ref, "--json"],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)["relmse"]


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--scenes", nargs="+", default=["cornell", "glassball"],
                    choices=list(references.SCENES))
    ap.add_argument("--targets", nargs="+", type=float, default=[0.03, 0.01, 0.003])
    ap.add_argument("--seed", type=int, default=7, help="seed of the renders (the reference's is 1)")
    ap.add_argument("--out", default=os.path.join(HERE, "results", "adaptive.json"))
    args = ap.parse_args()

    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(args.build, "pocl-cache"))
    exe = os.path.join(args.build, "apps/raytrace/sluice-raytrace")
    result = {"cpu": references.cpu_model(), "cores": os.cpu_count(),
              "load_average_at_start": os.getloadavg()[0],
              "command": " ".join(["bench/bench_adaptive.py"] + sys.argv[1:]), "scenes": {}}
    print(f"CPU: {result['cpu']}, {result['cores']} cores, load {result['load_average_at_start']:.2f}")
    print(f"{'scene':10} {'target':>7} {'mode':9} {'spp':>5} {'pixel samples':>14} "
          f"{'seconds':>8} {'estimate':>9} {'true relMSE':>11}")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            cfg = references.SCENES[scene]
            subprocess.run([sys.executable, os.path.join(HERE, "references.py"), "--scenes", scene,
                            "--seeds", "1", "--exe", exe], check=True, env=env)
            ref = os.path.join(HERE, "references", f"{scene}-sluice-s1.exr")
            with open(os.path.join(HERE, "references", f"{scene}-sluice-s1.json")) as f:
                rj = json.load(f)
            rows = []
            for target in args.targets:
                for mode in ("adaptive", "uniform"):
                    img = os.path.join(tmp, "a.exr")
                    stats = os.path.join(tmp, "a.json")
                    cmd = [exe, "--scene", scene, "--mode", "path", "--size", rj["size"],
                           "--light-samples", str(rj["light_samples"]), "--max-depth",
                           str(rj["max_depth"]), "--seed", str(args.seed), "--target-error",
                           str(target), "--exec", "fused", "--no-profile", "--quiet", "--out",
                           img, "--stats", stats]
                    if mode == "uniform":
                        cmd.append("--no-adaptive")
                    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
                    with open(stats) as f:
                        s = json.load(f)
                    samp = s["sampling"]
                    row = {"target": target, "mode": mode, "spp": s["spp"],
                           "pixel_samples": samp["pixel_samples"], "seconds": s["seconds"],
                           "estimate": samp["error"], "true_relmse": relmse(args.build, img, ref),
                           "tiles_stopped": samp["tiles"] - samp["tiles_active"]}
                    rows.append(row)
                    print(f"{scene:10} {target:7.3g} {mode:9} {row['spp']:5d} "
                          f"{row['pixel_samples']:14d} {row['seconds']:8.2f} "
                          f"{row['estimate']:9.3g} {row['true_relmse']:11.3g}", flush=True)
            result["scenes"][scene] = {"size": rj["size"], "reference_spp": rj["spp"],
                                       "runs": rows}
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
