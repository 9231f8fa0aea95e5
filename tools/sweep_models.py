#!/usr/bin/env python3
"""Reliability sweep (issue 12, item 8): runs the CLIs over every file of
Debian's assimp-testmodels package (about 600 files in about 40 formats, some
broken on purpose) and classifies each run:

  loaded        exit 0 with the expected output (sluice-scene: a statistics
                table with finite bounds; a renderer: a non-empty image)
  clean error   non-zero exit with a message on stderr naming the file
  crash         killed by a signal, or a sanitizer report on stderr
  hang          still running after --timeout seconds
  oom           stopped by the sweep's address-space limit (--mem-mb): the
                message says bad_alloc or out of memory; without the limit
                such a file takes the machine's memory (and then some time)
  silent        exit 0 without the expected output, or a non-zero exit whose
                message does not name the file

Usage: tools/sweep_models.py [--build DIR] [--cli scene,raytrace,photonmap]
                             [--timeout S] [--mem-mb N] [--jobs N] [--out DIR]
                             [--models DIR] [--only SUBSTRING]
The renderers only get the files sluice-scene loads (the same loader decides
for all three; a file it refuses is refused by them too, which the sweep
checks on a sample of them). Per-run results go to OUT/sweep-<cli>.tsv, the
summary to stdout; the exit status is 1 when any run crashed, hung, ran out of
memory or failed silently. Not part of `make test`: `make sweep` runs it.
"""
import argparse
import concurrent.futures
import math
import os
import re
import resource
import subprocess
import sys
import tempfile

SANITIZER = re.compile(r"AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer|runtime error:")
CLASSES = ["loaded", "clean error", "crash", "hang", "oom", "silent"]
BAD = ("crash", "hang", "oom", "silent")
OOM = re.compile(r"bad_alloc|out of memory", re.I)


def model_files(root):
    out = []
    for d, _, files in os.walk(root):
        for f in files:
            p = os.path.join(d, f)
            if os.path.isfile(p) and not os.path.islink(p):
                out.append(p)
    return sorted(out)


def limit_memory(mb):
    def apply():
        if mb > 0:
            b = mb << 20
            resource.setrlimit(resource.RLIMIT_AS, (b, b))
    return apply


def command(cli, build, path, image):
    if cli == "scene":
        return [os.path.join(build, "apps/common/sluice-scene"), path]
    exe = os.path.join(build, "apps", cli, "sluice-" + cli)
    return [exe, "--scene", path, "--size", "16x16", "--spp", "1", "--out", image, "--quiet",
            "--no-profile"]


def scene_output_ok(stdout):
    m = re.search(r"^bounds\s+min \(([^)]*)\)\s+max \(([^)]*)\)", stdout, re.M)
    t = re.search(r"^triangles\s+(\d+)", stdout, re.M)
    if not m or not t or int(t.group(1)) == 0:
        return False
    try:
        vals = [float(x) for x in (m.group(1) + "," + m.group(2)).split(",")]
    except ValueError:
        return False
    return all(math.isfinite(v) for v in vals)


def run_one(cli, build, path, timeout, mem_mb, tmpdir):
    image = os.path.join(tmpdir, "%d-%s.png" % (abs(hash(path)), cli))
    cmd = command(cli, build, path, image)
    try:
        p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, timeout=timeout,
                           preexec_fn=limit_memory(mem_mb))
    except subprocess.TimeoutExpired:
        return "hang", "over %g s" % timeout
    out = p.stdout.decode("utf-8", "replace")
    err = p.stderr.decode("utf-8", "replace")
    first = next((ln for ln in err.splitlines() if ln.strip()), "")
    if p.returncode < 0 or SANITIZER.search(err):
        what = "signal %d" % -p.returncode if p.returncode < 0 else "sanitizer"
        rep = next((ln for ln in err.splitlines() if SANITIZER.search(ln)), first)
        return "crash", "%s: %s" % (what, rep.strip()[:300])
    if p.returncode == 0:
        if cli == "scene":
            ok = scene_output_ok(out)
        else:
            ok = os.path.isfile(image) and os.path.getsize(image) > 0
        if os.path.exists(image):
            os.unlink(image)
        return ("loaded", "") if ok else ("silent", "exit 0 without the expected output")
    if OOM.search(err):
        return "oom", first.strip()[:300]
    named = os.path.basename(path) in err
    return ("clean error" if named else "silent"), first.strip()[:300]


def sweep(cli, build, files, args, tmpdir):
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as ex:
        futs = {ex.submit(run_one, cli, build, f, args.timeout, args.mem_mb, tmpdir): f
                for f in files}
        for fut in concurrent.futures.as_completed(futs):
            results[futs[fut]] = fut.result()
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "sweep-%s.tsv" % cli), "w") as f:
        for path in sorted(results):
            cls, note = results[path]
            f.write("%s\t%s\t%s\n" % (cls, path, note.replace("\t", " ").replace("\n", " ")))
    counts = {c: 0 for c in CLASSES}
    for cls, _ in results.values():
        counts[cls] += 1
    print("sluice-%-10s %4d files: %s" % (cli, len(files), ", ".join(
        "%d %s" % (counts[c], c) for c in CLASSES)))
    for path in sorted(results):
        cls, note = results[path]
        if cls in BAD:
            print("  %-6s %s: %s" % (cls, path, note))
    sys.stdout.flush()
    return results


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--cli", default="scene,raytrace,photonmap")
    ap.add_argument("--models", default="/usr/share/assimp/models")
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--mem-mb", type=int, default=4096,
                    help="address-space limit per run (0: none; use 0 under ASan)")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=None)
    ap.add_argument("--only", default="", help="only paths containing this")
    ap.add_argument("--refused-sample", type=int, default=40,
                    help="files sluice-scene refuses that the renderers also get")
    args = ap.parse_args()
    if args.out is None:
        args.out = os.path.join(args.build, "sweep")
    if not os.path.isdir(args.models):
        sys.exit("%s: no such directory (apt-get install assimp-testmodels)" % args.models)
    files = [f for f in model_files(args.models) if args.only in f]
    clis = [c for c in args.cli.split(",") if c]
    bad = 0
    with tempfile.TemporaryDirectory(prefix="sluice-sweep-") as tmpdir:
        scene_results = None
        for cli in clis:
            todo = files
            if cli != "scene" and scene_results is not None:
                loaded = [f for f in files if scene_results[f][0] == "loaded"]
                refused = [f for f in files if scene_results[f][0] != "loaded"]
                step = max(1, len(refused) // max(1, args.refused_sample))
                todo = loaded + refused[::step][: args.refused_sample]
            res = sweep(cli, args.build, todo, args, tmpdir)
            if cli == "scene":
                scene_results = res
            bad += sum(1 for c, _ in res.values() if c in BAD)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
