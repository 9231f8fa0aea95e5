#!/usr/bin/env python3
"""Run time against error (Davidovic's thesis, sections 4.4.4 and 4.7): each
method renders a scene at increasing effort, and every image's relMSE and
RMSE against the converged reference (bench/references.py) is recorded with
the render's own time. Methods:

  path          sluice-raytrace --mode path, 1, 2, 4, ... samples per pixel
  pm-count-kK   sluice-photonmap, count build, Purcell's at-least-k search,
                one sample, more photons each step (the estimate's bias and
                noise shrink with the photons, k fixed)
  ppm           sluice-photonmap --progressive, 1, 2, 4, ... samples (new
                photons and a smaller radius each)

  bench/bench_error.py [--scene glassball] [--build build] [--out bench/results/error.json]
                       [--quick]

Writes JSON naming the CPU: per method, the (seconds, relMSE, RMSE) points,
and the time each method needs to reach a few relMSE levels (interpolated in
log-log between the points around it; null when not reached). Prints the
table. With matplotlib importable it also draws error against seconds,
log-log, to bench/results/error-SCENE.png. The references are renders of
Sluice's own path tracer, checked against Mitsuba 3 by
bench/mitsuba_compare.py (bench/README.md)."""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import references  # noqa: E402  (bench/references.py: sizes, cpu_model)

LEVELS = [1e-1, 3e-2, 1e-2, 3e-3, 1e-3]


def imgdiff(build, img, ref):
    out = subprocess.run([os.path.join(build, "apps/common/sluice-imgdiff"), img, ref, "--json"],
                         capture_output=True, text=True, check=True).stdout
    d = json.loads(out)
    return d["relmse"], d["rmse"]


def render(cmd, stats):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(stats) as f:
        s = json.load(f)
    return s["phases"]["total"] if "phases" in s else s["seconds"]


def time_to(points, level):
    """Seconds at which the error first falls to `level`, interpolated in
    log-log between the two points around it (None if never)."""
    pts = sorted(points)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 > level >= e1 and e0 > 0 and e1 > 0:
            f = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    if pts and pts[0][1] <= level:
        return pts[0][0]
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default="glassball", choices=sorted(references.SCENES))
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench/results/error.json"))
    ap.add_argument("--quick", action="store_true", help="fewer, cheaper steps")
    a = ap.parse_args()
    sc = references.SCENES[a.scene]
    ref = os.path.join(HERE, "references", "%s-sluice-s1.exr" % a.scene)
    if not os.path.exists(ref):
        subprocess.run([sys.executable, os.path.join(HERE, "references.py"), "--scenes", a.scene,
                        "--seeds", "1"], check=True)
    rt = os.path.join(a.build, "apps/raytrace/sluice-raytrace")
    pm = os.path.join(a.build, "apps/photonmap/sluice-photonmap")
    n = 4 if a.quick else 8
    common = ["--scene", a.scene, "--size", sc["size"], "--quiet", "--no-profile"]
    methods = {
        "path": [[rt, "--mode", "path", "--light-samples", "1", "--max-depth", "5", "--spp",
                  str(1 << i)] for i in range(n)],
        "ppm": [[pm, "--progressive", "--photons", "5000", "--spp", str(1 << i)]
                for i in range(n)],
    }
    for k in (32, 128):
        methods["pm-count-k%d" % k] = [[pm, "--k", str(k), "--photons", str(5000 << i)]
                                       for i in range(n - 2)]
    res = {"cpu": references.cpu_model(), "scene": a.scene, "size": sc["size"],
           "reference": os.path.relpath(ref, ROOT), "command": " ".join(sys.argv),
           "levels": LEVELS, "methods": {}}
    with tempfile.TemporaryDirectory() as tmp:
        img, stats = os.path.join(tmp, "img.exr"), os.path.join(tmp, "s.json")
        for name, steps in methods.items():
            points = []
            subprocess.run(steps[0] + common + ["--out", img], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # warm PoCL's cache
            for cmd in steps:
                t = render(cmd + common + ["--out", img, "--stats", stats], stats)
                rel, rmse = imgdiff(a.build, img, ref)
                points.append({"seconds": t, "relmse": rel, "rmse": rmse,
                               "args": " ".join(cmd[1:])})
                print("%-14s %8.3f s  relMSE %.4g  RMSE %.4g  (%s)" % (name, t, rel, rmse,
                                                                    " ".join(cmd[1:])))
            tt = {str(l): time_to([(p["seconds"], p["relmse"]) for p in points], l)
                  for l in LEVELS}
            res["methods"][name] = {"points": points, "seconds_to_relmse": tt}
    print("\nseconds to reach relMSE (%s, %s, %s):" % (a.scene, sc["size"], res["cpu"]))
    print("%-14s" % "method" + "".join("%10g" % l for l in LEVELS))
    for name, m in res["methods"].items():
        print("%-14s" % name + "".join(
            "%10s" % ("%.3g" % m["seconds_to_relmse"][str(l)]
                      if m["seconds_to_relmse"][str(l)] is not None else "-") for l in LEVELS))
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
        f.write("\n")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(no matplotlib: no plot)")
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    for name, m in res["methods"].items():
        ax.loglog([p["seconds"] for p in m["points"]], [p["relmse"] for p in m["points"]],
                  marker="o", label=name)
    ax.set_xlabel("seconds")
    ax.set_ylabel("relMSE against the reference")
    ax.set_title("%s %s, %s" % (a.scene, sc["size"], res["cpu"]), fontsize=8)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(os.path.dirname(a.out), "error-%s.png" % a.scene), dpi=100)


if __name__ == "__main__":
    main()
