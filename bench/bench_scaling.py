#!/usr/bin/env python3
"""Parallel scaling of the stream primitives and the ray tracer on a CPU.

Runs bench_streams (2^24 records) and bench_raytrace (cornell, bunny, bunny-close) once
per thread count, each limited to that many cores (taskset) and PoCL threads
(POCL_MAX_PTHREAD_COUNT for PoCL 3, POCL_CPU_MAX_CU_COUNT for PoCL 4 and 5),
and writes one JSON file: every run's figures, and per figure the speedup
over one thread and the parallel efficiency (speedup / threads). For the
memory-bound primitives it also gives the copy kernel's own speedup, the
bound that no primitive can pass on a machine whose memory bandwidth does not
grow with the cores.

  bench/bench_scaling.py [--threads 1,2,4,8,16] [--build build]
                         [--out bench/results/scaling.json] [--keep DIR]
  bench/bench_scaling.py --merge DIR --out FILE   (from earlier runs' files:
                         DIR/streams-N.json, DIR/raytrace-N.json)
"""
import argparse
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

SCENES = ("cornell", "bunny", "bunny-close")


def run_one(build, n, tmp):
    env = dict(os.environ, POCL_MAX_PTHREAD_COUNT=str(n), POCL_CPU_MAX_CU_COUNT=str(n))
    pin = ["taskset", "-c", "0-%d" % (n - 1)]
    s_out = os.path.join(tmp, "streams-%d.json" % n)
    r_out = os.path.join(tmp, "raytrace-%d.json" % n)
    print("== %d thread%s" % (n, "" if n == 1 else "s"), flush=True)
    subprocess.run(pin + [os.path.join(build, "bench", "bench_streams"), "--reps", "3",
                          "--skip-bitonic", "--out", s_out], env=env, check=True)
    cmd = [os.path.join(build, "bench", "bench_raytrace"), "--skip-purcell", "--reps", "2",
           "--out", r_out]
    for s in SCENES:
        cmd += ["--scene", s]
    subprocess.run(pin + cmd, env=env, check=True)


def merge(folder, command):
    streams, rays = {}, {}
    for f in glob.glob(os.path.join(folder, "streams-*.json")):
        streams[int(re.search(r"streams-(\d+)\.json$", f).group(1))] = json.load(open(f))
    for f in glob.glob(os.path.join(folder, "raytrace-*.json")):
        rays[int(re.search(r"raytrace-(\d+)\.json$", f).group(1))] = json.load(open(f))
    threads = sorted(streams)
    if not threads or 1 not in streams:
        sys.exit("bench_scaling: no streams-1.json in %s" % folder)
    one = streams[1]

    def scaled(values):
        base = values[threads[0]] if threads[0] == 1 else None
        return {str(n): {"value": round(values[n], 3),
                         "speedup": round(values[n] / base, 3) if base else None,
                         "efficiency": round(values[n] / base / n, 3) if base else None}
                for n in threads if n in values}

    res = {"cpu": one.get("cpu"), "cpu_isa": one.get("cpu_isa"), "device": one.get("device"),
           "command": command, "threads": threads, "records": one.get("records"),
           "copy_gb_per_s": scaled({n: streams[n]["copy_gb_per_s"] for n in threads}),
           "launch_chain_us_per_launch": {str(n): streams[n]["launch_chain_us_per_launch"]
                                          for n in threads},
           "primitives_m_records_per_s": {}, "fraction_of_copy": {}, "ray_tracer_m_rays_per_s": {}}
    for p in one["primitives"]:
        name = p["name"]
        vals = {n: next(q["records_per_s"] for q in streams[n]["primitives"] if q["name"] == name) / 1e6
                for n in threads}
        res["primitives_m_records_per_s"][name] = scaled(vals)
        res["fraction_of_copy"][name] = {
            str(n): next(q["fraction_of_copy"] for q in streams[n]["primitives"] if q["name"] == name)
            for n in threads}
    if 1 in rays:
        for scene in SCENES:
            for kind in ("primary", "bounce"):
                for peer in ("sluice_fused", "sluice_stream"):
                    vals = {}
                    for n in threads:
                        sc = [s for s in rays.get(n, {}).get("scenes", []) if s["scene"] == scene]
                        if sc:
                            rp = sc[0]["rays_per_second"] if kind == "primary" else \
                                sc[0]["bounce"]["rays_per_second"]
                            vals[n] = rp[peer] / 1e6
                    if 1 in vals:
                        res["ray_tracer_m_rays_per_s"]["%s %s %s" % (scene, kind, peer)] = scaled(vals)
    return res


def report(res):
    t = res["threads"]
    print("CPU: %s (%s), device %s" % (res["cpu"], res["cpu_isa"], res["device"]))
    print("%-34s %s" % ("threads", " ".join("%8d" % n for n in t)))

    def row(name, d):
        print("%-34s %s   efficiency at %d: %3.0f%%" % (
            name, " ".join("%8.1f" % d[str(n)]["value"] for n in t), t[-1],
            100 * (d[str(t[-1])]["efficiency"] or 0)))

    row("copy GB/s", res["copy_gb_per_s"])
    for name, d in res["primitives_m_records_per_s"].items():
        row(name + " M/s", d)
    for name, d in res["ray_tracer_m_rays_per_s"].items():
        row(name.replace("sluice_", "") + " M rays/s", d)
    print("%-34s %s" % ("launch chain us/launch",
                        " ".join("%8.1f" % res["launch_chain_us_per_launch"][str(n)] for n in t)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", default=None,
                    help="comma-separated thread counts, run in this order, 1 first (default: 1, "
                         "2, 4, ... up to all cores)")
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default="bench/results/scaling.json")
    ap.add_argument("--keep", help="keep each run's JSON files in this folder")
    ap.add_argument("--merge", help="no runs: merge the files of earlier runs in this folder")
    a = ap.parse_args()
    if a.merge:
        res = merge(a.merge, " ".join(sys.argv))
    else:
        if a.threads:
            # in the order given, so that a run cut short (a lent machine's
            # time limit) still has the counts that matter most: 1,16,2,8,4
            threads = list(dict.fromkeys(int(x) for x in a.threads.split(",")))
        else:
            cores, threads, n = len(os.sched_getaffinity(0)), [], 1
            while n < cores:
                threads.append(n)
                n *= 2
            threads.append(cores)
        folder = a.keep or tempfile.mkdtemp(prefix="sluice-scaling-")
        if threads[0] != 1 and not os.path.exists(os.path.join(folder, "streams-1.json")):
            sys.exit("bench_scaling: the thread counts must start at 1 (the base of the speedups), "
                     "unless the --keep folder holds a run on 1 thread")
        os.makedirs(folder, exist_ok=True)
        for n in threads:
            run_one(a.build, n, folder)
        res = merge(folder, " ".join(sys.argv))
    report(res)
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
