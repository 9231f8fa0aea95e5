#!/usr/bin/env python3
"""Purcell's Table 6.1 side by side: his three scenes at his settings (image
size, photons, k, grid, light samples) rendered by sluice-photonmap with each
photon-map build, each phase beside his GeForce FX 5900 Ultra times.

  bench/bench_photonmap.py [--exe build/apps/photonmap/sluice-photonmap]
                           [--out bench/results/photonmap.json] [--reps R] [--quick]

Writes JSON naming the CPU; prints a table. Times are host wall times: each
configuration runs once to warm PoCL's cache (the first render also builds
the kernels), then R times (default 3), and the run with the lowest total
is kept, its phases with it; every run's total is recorded beside it
(totals_s), so that the spread of a shared machine shows. Setup, the
renderer's creation with its kernels built, comes before the phases and is
recorded beside them (setup_s), not in them.

Each build runs twice: with the defaults (the stream tracer, one kNN shell
per pass: Purcell's passes) and with the fastest options that give the same
image ("fast": --exec fused --shells-per-pass all; the tracer's two modes
give the same hits, and the shells are the same in the same order, so the
estimates take the same photons, summed in another order: test_raytrace
and test_knn check it)."""
import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile

# Purcell 2004, Table 6.1 (seconds): bitonic / stencil totals, and his settings
PURCELL = {
    "glassball": {"size": "512x384", "photons": 5000, "k": 32, "grid": "250x1x250",
                  "light_samples": 4, "bitonic": 17.4, "stencil": 11.3},
    "ring": {"size": "512x384", "photons": 16000, "k": 64, "grid": "250x1x250",
             "light_samples": 1, "bitonic": 9.0, "stencil": 8.1},
    "cornell": {"size": "512x512", "photons": 65000, "k": 500, "grid": "25x25x50",
                "light_samples": 32, "bitonic": 64.3, "stencil": 47.2},
}


def cpu_name():
    """The model name, family and model (the name alone can be generic in a
    virtual machine) and the widest vector ISA, from /proc/cpuinfo."""
    try:
        with open("/proc/cpuinfo") as f:
            text = f.read()
    except OSError:
        return platform.processor() or "unknown"
    first = {}
    for line in text.splitlines():
        key, _, value = line.partition(":")
        first.setdefault(key.strip(), value.strip())
    name = first.get("model name", "unknown")
    if "cpu family" in first and "model" in first:
        name += " (family %s, model %s)" % (first["cpu family"], first["model"])
    return name + (" (AVX-512)" if "avx512f" in text else " (AVX2, no AVX-512)")


FAST = ["--exec", "fused", "--shells-per-pass", "all"]


def run(exe, scene, s, build, quick, tmp, extra=(), device=None):
    stats = os.path.join(tmp, "s.json")
    size = "128x96" if quick else s["size"]
    cmd = [exe, "--scene", scene, "--size", size, "--photons", str(s["photons"]),
           "--k", str(s["k"]), "--grid", s["grid"], "--light-samples", str(s["light_samples"]),
           "--map", build, "--no-image", "--stats", stats, "--quiet",
           "--no-profile"] + list(extra) + (["--device", device] if device else [])
    subprocess.run(cmd, check=True)
    with open(stats) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--exe", default="build/apps/photonmap/sluice-photonmap")
    ap.add_argument("--out", default="bench/results/photonmap.json")
    ap.add_argument("--quick", action="store_true", help="small images, for the smoke test")
    ap.add_argument("--reps", type=int, default=None,
                    help="timed runs per configuration, the fastest kept (default 3; 1 with --quick)")
    ap.add_argument("--device", help="OpenCL device (substring of \"platform / device\"; "
                    "default: the first CPU device)")
    a = ap.parse_args()
    reps = a.reps if a.reps is not None else (1 if a.quick else 3)
    if reps < 1:
        ap.error("--reps must be at least 1")
    device = None
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene, s in PURCELL.items():
            for build, options in [(b, o) for o in ("default", "fast")
                                   for b in ("bitonic", "stencil", "count")]:
                extra = FAST if options == "fast" else ()
                run(a.exe, scene, s, build, True, tmp, extra, a.device)  # warm the kernel cache
                runs = [run(a.exe, scene, s, build, a.quick, tmp, extra, a.device)
                        for _ in range(reps)]
                r = min(runs, key=lambda x: x["phases"]["total"])
                device = r.get("device", device)
                ph = r["phases"]
                row = {"scene": scene, "build": build, "options": options,
                       "size": s["size"] if not a.quick else "128x96",
                       "photons": s["photons"], "k": s["k"], "grid": s["grid"],
                       "light_samples": s["light_samples"], "phases_s": ph,
                       "setup_s": r.get("setup_s"),
                       "totals_s": [x["phases"]["total"] for x in runs],
                       "stored": r["photons"]["stored"], "emitted": r["photons"]["emitted"],
                       "mean_photons": r["estimates"]["mean_photons"],
                       "stencil_overflow": r["map_grid"]["overflow_points"]}
                if build in s:
                    row["purcell_total_s"] = s[build]
                    row["speedup"] = s[build] / ph["total"]
                rows.append(row)
                totals = row["totals_s"]
                print("%-9s %-7s %-7s trace photons %6.3f  build %6.3f  trace rays %6.3f  estimate "
                      "%6.3f  total %6.3f s%s%s" % (scene, build, options, ph["trace_photons"], ph["build_map"],
                                                    ph["trace_rays"], ph["radiance_estimate"],
                                                    ph["total"],
                                                    " (of %.3f-%.3f)" % (min(totals), max(totals))
                                                    if reps > 1 else "",
                                                    "  Purcell %5.1f s: %.0fx" % (s[build], row["speedup"])
                                                    if build in s else ""))
    res = {"cpu": cpu_name(), "device": device, "command": " ".join(sys.argv), "quick": a.quick,
           "reps": reps, "results": rows}
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
