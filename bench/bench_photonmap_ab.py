#!/usr/bin/env python3
"""A photon-mapper render against a variant of itself, phase by phase and
kernel by kernel, to tell a change of a few percent from the noise of a
shared machine (bench_knn_ab and bench_raytrace_ab do the same in one
process for the search and the tracer).

  bench/bench_photonmap_ab.py [--exe-a EXE] [--exe-b EXE] [--a OPTIONS] [--b OPTIONS]
                              [--scene glassball|ring|cornell] [--map bitonic|stencil|count]
                              [--defaults] [--rounds N] [--spp N] [--args "OPTIONS"]
                              [--quick] [--device NAME]

Variant A is --exe-a with the kernel build options --a (SLUICE_BUILD_OPTIONS),
variant B --exe-b with --b: two builds of the renderer (an older commit's, in
a git worktree, against this one), or one build with a change behind an
#ifdef. Both render one of Purcell's Table 6.1 scenes at his settings
(bench_photonmap.py's), with --exec fused --shells-per-pass all unless
--defaults. Each renders once to warm PoCL's cache, then they alternate,
A B then B A, for --rounds rounds, so that drift in the machine's speed falls
on both alike. Printed per phase and per kernel (the renderer's profile, in
its --stats file): A's and B's medians and the median over rounds of B's
speed over A's (A's time over B's) with its quartiles.

Whole renders drift more than one process's calls do: a null run
(--b=-DNOTHING_AT_ALL) shows how far apart two equal variants come out on
the machine at hand (bench/README.md).

Exit status 0, or 2 on bad arguments or a render that failed."""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_photonmap import FAST, PURCELL, cpu_name  # noqa: E402

PHASES = ["trace_photons", "build_map", "trace_rays", "radiance_estimate", "total"]


def render(exe, options, args, stats, device):
    env = dict(os.environ)
    env["SLUICE_BUILD_OPTIONS"] = options
    cmd = [exe] + args + ["--no-image", "--quiet", "--stats", stats]
    if device:
        cmd += ["--device", device]
    r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.stderr.write(r.stdout)
        sys.stderr.write("bench_photonmap_ab: %s failed (exit status %d)\n" % (exe, r.returncode))
        sys.exit(2)
    with open(stats) as f:
        d = json.load(f)
    t = {"phase " + p: d["phases"][p] for p in PHASES}
    for k in d.get("kernels", []):
        t[k["name"]] = t.get(k["name"], 0.0) + k["seconds"]
    return t


def quartiles(v):
    v = sorted(v)
    if len(v) < 2:
        return v[0], v[0], v[0]
    q = statistics.quantiles(v, n=4, method="inclusive")
    return q[0], q[1], q[2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe-a", default="build/apps/photonmap/sluice-photonmap")
    ap.add_argument("--exe-b", default="build/apps/photonmap/sluice-photonmap")
    ap.add_argument("--a", default="", help="kernel build options for A (default none; write --a=-DNAME)")
    ap.add_argument("--b", default="", help="kernel build options for B (default none; write --b=-DNAME)")
    ap.add_argument("--scene", default="ring", choices=sorted(PURCELL))
    ap.add_argument("--map", default="stencil", choices=["bitonic", "stencil", "count"])
    ap.add_argument("--defaults", action="store_true",
                    help="the renderer's defaults (stream tracer, one shell a pass), not "
                    "--exec fused --shells-per-pass all")
    ap.add_argument("--rounds", type=int, default=10, help="A B / B A rounds (default 10)")
    ap.add_argument("--spp", type=int, default=1,
                    help="samples per pixel: each traces the rays and estimates again "
                    "(default 1, Purcell's)")
    ap.add_argument("--args", default="",
                    help="more sluice-photonmap options for both, one string "
                    "(e.g. --args=\"--progressive --spp 8\")")
    ap.add_argument("--kernels", type=int, default=8,
                    help="kernels shown, the slowest first (default 8)")
    ap.add_argument("--quick", action="store_true", help="128x96 images, for the smoke test")
    ap.add_argument("--device", help="OpenCL device (substring of \"platform / device\")")
    a = ap.parse_args()
    if a.rounds < 1:
        ap.error("--rounds must be at least 1")
    if a.spp < 1:
        ap.error("--spp must be at least 1")
    for exe in (a.exe_a, a.exe_b):
        if not os.access(exe, os.X_OK):
            ap.error("%s: not an executable (build first, or name it)" % exe)
    s = PURCELL[a.scene]
    args = ["--scene", a.scene, "--size", "128x96" if a.quick else s["size"],
            "--photons", str(s["photons"]), "--k", str(s["k"]), "--grid", s["grid"],
            "--light-samples", str(s["light_samples"]), "--map", a.map, "--spp", str(a.spp)]
    if not a.defaults:
        args += FAST
    args += a.args.split()
    variants = [(a.exe_a, a.a), (a.exe_b, a.b)]
    times = [[], []]
    with tempfile.TemporaryDirectory() as tmp:
        stats = os.path.join(tmp, "s.json")
        for exe, opt in variants:
            render(exe, opt, args, stats, a.device)  # warm PoCL's cache
        for r in range(a.rounds):
            for v in ((0, 1) if r % 2 == 0 else (1, 0)):
                times[v].append(render(variants[v][0], variants[v][1], args, stats, a.device))
    print("%s; %s, map %s%s; A: %s '%s', B: %s '%s'; %d rounds (A B, B A)" % (
        cpu_name(), a.scene, a.map, " (defaults)" if a.defaults else " (fused, all shells)",
        a.exe_a, a.a, a.exe_b, a.b, a.rounds))
    names = ["phase " + p for p in PHASES]
    # kernels of either (an older build may write no profile): slowest first
    kern = sorted({k for v in times for t in v for k in t if not k.startswith("phase ")},
                  key=lambda k: -max(statistics.median([t.get(k, 0.0) for t in v])
                                     for v in times))
    names += kern[:a.kernels]
    print("%-28s %10s %10s %10s  %s" % ("", "A ms", "B ms", "B speed/A", "quartiles"))
    for n in names:
        ta = [t.get(n, 0.0) for t in times[0]]
        tb = [t.get(n, 0.0) for t in times[1]]
        ratios = [x / y for x, y in zip(ta, tb) if x > 0 and y > 0]
        if not ratios:
            print("%-28s %10.2f %10.2f %10s" % (n, 1e3 * statistics.median(ta),
                                                1e3 * statistics.median(tb), "-"))
            continue
        q1, med, q3 = quartiles(ratios)
        print("%-28s %10.2f %10.2f %9.3fx  %.3f-%.3f" % (
            n, 1e3 * statistics.median(ta), 1e3 * statistics.median(tb), med, q1, q3))


if __name__ == "__main__":
    main()
