#!/usr/bin/env python3
"""Converged reference images of the built-in scenes, rendered by Sluice's
path tracer (sluice-raytrace --mode path) at high sample counts.

Each reference is bench/references/<scene>-sluice-s<seed>.exr (linear float)
with a JSON beside it: scene, size, spp, seed, light samples, max depth,
seconds, the CPU (lscpu's model name), the git commit and the command. A
reference whose JSON already records the same scene, size, spp, seed, light
samples and max depth is kept (cached) unless --force is given. The folder is
git-ignored: references are regenerated, never committed.

Two seeds per scene (the default) give two independent estimates: their
difference measures the noise left in the references, the noise floor that
bench/mitsuba_compare.py judges the agreement with Mitsuba 3 against.

--kind ppm renders the scenes that name "ppm_spp" (ring) with
sluice-photonmap --progressive instead, into <scene>-sluice-ppm-s<seed>.exr:
ring's caustic (a point light seen in a mirror) is a path that no
unidirectional path tracer samples, so its path-traced reference lacks it,
while progressive photon mapping converges to it (bench/bench_error.py
judges ring against this reference).
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# Size and samples per pixel of each scene's reference: the scene camera's
# aspect at a small size, so that generation stays within minutes on 2 cores.
SCENES = {
    "cornell": {"size": "128x128", "spp": 2048},
    "glassball": {"size": "160x120", "spp": 1024},
    "ring": {"size": "160x120", "spp": 512, "ppm_spp": 1024, "ppm_photons": 16000},
}


def ref_base(folder, scene, seed, kind="path"):
    """bench/references/<scene>-sluice[-ppm]-s<seed> (no extension)."""
    return os.path.join(folder, "%s-sluice%s-s%d" % (scene, "" if kind == "path" else "-ppm", seed))


def cpu_model():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except (OSError, subprocess.CalledProcessError):
        pass
    return "unknown"


def git_commit():
    try:
        return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--exe", default=os.path.join(ROOT, "build/apps/raytrace/sluice-raytrace"),
                    help="sluice-raytrace executable (default: build/apps/raytrace/)")
    ap.add_argument("--pm-exe", default=os.path.join(ROOT, "build/apps/photonmap/sluice-photonmap"),
                    help="sluice-photonmap executable, for --kind ppm")
    ap.add_argument("--kind", choices=["path", "ppm"], default="path",
                    help="path: path-traced references (default); ppm: progressive photon "
                    "mapping, for the scenes that name ppm_spp (ring)")
    ap.add_argument("--out", default=os.path.join(HERE, "references"),
                    help="output folder (default: bench/references)")
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES),
                    help="scenes to render (default: all)")
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2],
                    help="one reference per seed (default: 1 2)")
    ap.add_argument("--spp", type=int, help="samples per pixel (default: per scene)")
    ap.add_argument("--size", help="WxH (default: per scene)")
    ap.add_argument("--light-samples", type=int, default=1,
                    help="shadow rays per area light and hit (default 1)")
    ap.add_argument("--max-depth", type=int, default=5,
                    help="path max depth (default 5, the scenes' own)")
    ap.add_argument("--force", action="store_true", help="render even when cached")
    args = ap.parse_args()

    os.makedirs(args.out, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(ROOT, "build", "pocl-cache"))
    cpu = cpu_model()
    for scene in args.scenes:
        if args.kind == "ppm" and "ppm_spp" not in SCENES[scene]:
            continue
        size = args.size or SCENES[scene]["size"]
        spp = args.spp or SCENES[scene]["ppm_spp" if args.kind == "ppm" else "spp"]
        for seed in args.seeds:
            base = ref_base(args.out, scene, seed, args.kind)
            want = {"scene": scene, "size": size, "spp": spp, "seed": seed,
                    "light_samples": args.light_samples, "max_depth": args.max_depth}
            if args.kind == "ppm":
                want.update({"kind": "ppm", "photons": SCENES[scene]["ppm_photons"]})
            if not args.force and os.path.exists(base + ".exr") and os.path.exists(base + ".json"):
                with open(base + ".json") as f:
                    have = json.load(f)
                if all(have.get(k) == v for k, v in want.items()):
                    print("%s: cached (%s.exr, %.0f s)" % (scene, base, have.get("seconds", 0)))
                    continue
            if args.kind == "ppm":
                cmd = [args.pm_exe, "--scene", scene, "--progressive", "--size", size,
                       "--spp", str(spp), "--seed", str(seed),
                       "--photons", str(SCENES[scene]["ppm_photons"]),
                       "--light-samples", str(args.light_samples),
                       "--max-depth", str(args.max_depth), "--no-profile"]
            else:
                cmd = [args.exe, "--scene", scene, "--mode", "path", "--size", size,
                       "--spp", str(spp), "--seed", str(seed),
                       "--light-samples", str(args.light_samples),
                       "--max-depth", str(args.max_depth)]
            cmd += ["--out", base + ".exr", "--stats", base + ".stats.json", "--quiet"]
            print("%s seed %d: %s" % (scene, seed, " ".join(cmd)), flush=True)
            t0 = time.time()
            subprocess.run(cmd, check=True, env=env)
            secs = time.time() - t0
            meta = dict(want)
            meta.update({"renderer": "sluice-photonmap --progressive" if args.kind == "ppm"
                         else "sluice-raytrace --mode path", "seconds": round(secs, 1),
                         "cpu": cpu, "cores": os.cpu_count(), "commit": git_commit(),
                         "command": " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT)
                                             else c for c in cmd)})
            with open(base + ".json", "w") as f:
                json.dump(meta, f, indent=2)
                f.write("\n")
            print("%s seed %d: %.1f s -> %s.exr" % (scene, seed, secs, base), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
