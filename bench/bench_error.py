#!/usr/bin/env python3
"""Run time against error (Davidovic's thesis, sections 4.4.4 and 4.7): each
method renders a scene at increasing effort, and every image's relMSE and
RMSE against a converged reference (bench/references.py) is recorded with
the render's own time; from the points, the time each method needs to reach
a few relMSE levels. Methods, per scene (cornell, glassball, ring):

  path             sluice-raytrace --mode path, 1, 2, 4, ... samples per pixel
  ppm              sluice-photonmap --progressive, 1, 2, 4, ... samples (new
                   photons and a smaller radius each): a slope is fitted to
                   log relMSE against log seconds (Knaus and Zwicker: MSE ~
                   N^(-2/3))
  path-fast,       the same with --exec fused (and --shells-per-pass all):
  ppm-fast         the same images, faster
  ppm-fast-2x      glassball: ppm-fast with twice the photons a pass (half the
                   eye passes for the same photons)
  pm-MAP-kK        sluice-photonmap, one sample, photon map built by MAP
                   (count, bitonic sort or stencil routing), Purcell's
                   at-least-k search, more photons each step (bias and noise
                   shrink with the photons, k fixed)
  mitsuba-path     Mitsuba 3's path tracer (variant llvm_ad_rgb, else
                   scalar_rgb) on `sluice-scene --export-mitsuba`, 1, 2, 4,
                   ... spp, in this process, in the same run
  povray-photons   POV-Ray 3.7 with photon-mapped caustics on the scene
                   converted by bench/pov_export.py (glassball and ring),
                   more photons, area-light samples and antialiasing each
                   step

  bench/bench_error.py [--scene S ...] [--build build] [--out bench/results/error.json]
                       [--plots bench/results] [--quick] [--no-mitsuba] [--no-povray]
                       [--povray-scene S ...] [--ref-seeds N]

Run it with bench/.venv/bin/python (tools/install-mitsuba.sh makes it) for
the Mitsuba figures and the plots; with a Python without Mitsuba or
matplotlib those are left out and the file says so.

The reference of a scene is the mean of its references' seeds
(bench/references/SCENE-sluice[-ppm]-sSEED.exr, all that are there, at
least seeds 1 .. REF_SEEDS: rendered first when missing): the path-traced
ones, except ring, whose caustics no path tracer samples (a point light
seen in a mirror), judged against a long progressive photon-mapping render. What is
left of the references' own noise adds to every relMSE measured against
them: the file records that floor (the relMSE between two seeds over 2n for
a mean of n seeds), and levels near it say little.

Sluice's renders use seed METHOD_SEED (1000), which no reference uses: a
method run with a reference's seed would repeat that reference's first
samples, and its error would come out too low.

Every time is the render's own, without start-up and program or scene
set-up: Sluice's `phases.total` / `seconds` (after a warm-up run that fills
PoCL's kernel cache), Mitsuba's mi.render() until the image is in memory
(after a warm-up render that compiles its kernels), POV-Ray's photon and
trace times as it reports them (parsing left out). A render under 2 s is
timed twice and the shorter time kept. The metric is
sluice-imgdiff's relMSE, mean over pixels and channels of (a - b)^2 / (b^2
+ 0.01), b the reference, for every renderer alike.

Writes JSON naming the CPU, the load average at the start and the command;
prints the table; draws error against seconds, log-log, one PNG per scene
(PLOTS/error-SCENE.png)."""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import pov_export  # noqa: E402  (bench/pov_export.py)
import references  # noqa: E402  (bench/references.py: sizes, cpu_model)

LEVELS = [1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 3e-4]
SCENES = ["cornell", "glassball", "ring"]
# Reference kind per scene (see the docstring) and the photon mapper's k.
REF_KIND = {"cornell": "path", "glassball": "path", "ring": "ppm"}
# Seeds averaged into the reference: glassball's caustic is the noisiest
# (2 seeds of 1,024 spp left a floor near 4e-4; 8 seeds, 1e-4).
REF_SEEDS = {"cornell": 2, "glassball": 8, "ring": 2}
# the seed of every Sluice method's renders: far from the references' 1 .. N
METHOD_SEED = 1000
PM_K = {"cornell": (128, 500), "glassball": (32, 128), "ring": (32, 128)}
MAPS = ("count", "bitonic", "stencil")
POVRAY_SCENES = ("glassball", "ring")
# POV-Ray's steps: (photons { count }, area-light samples per side, +R
# antialiasing depth), all three growing (POV-Ray's error on glassball is
# mostly the area light's sampling: 4 x 4 to 8 x 8 halved it).
POVRAY_STEPS = [(5000, 4, 1), (20000, 8, 1), (80000, 12, 1), (320000, 16, 2)]
MITSUBA_VARIANTS = ("llvm_ad_rgb", "scalar_rgb")


def run_quiet(cmd, env=None):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)


def imgdiff(build, img, ref):
    out = subprocess.run([os.path.join(build, "apps/common/sluice-imgdiff"), img, ref, "--json"],
                         capture_output=True, text=True, check=True).stdout
    d = json.loads(out)
    return d["relmse"], d["rmse"]


def render(cmd, stats, env):
    """The render's own seconds, or raises RuntimeError with its message."""
    out = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         env=env)
    if out.returncode != 0:
        raise RuntimeError(out.stderr.strip().splitlines()[-1] if out.stderr.strip()
                           else "exit status %d" % out.returncode)
    with open(stats) as f:
        s = json.load(f)
    return s["phases"]["total"] if "phases" in s else s["seconds"]


def time_to(points, level):
    """Seconds at which the error first falls to `level`, interpolated in
    log-log between the two points around it (None if never)."""
    pts = sorted(points)
    if pts and pts[0][1] <= level:
        return pts[0][0]
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 > level >= e1 and e0 > 0 and e1 > 0:
            f = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    return None


def error_at(points, seconds):
    """relMSE at `seconds`, interpolated in log-log between the points
    around it (None outside the points' span)."""
    pts = sorted(points)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if t0 <= seconds <= t1:
            f = (math.log(seconds) - math.log(t0)) / (math.log(t1) - math.log(t0))
            return math.exp(math.log(e0) + f * (math.log(e1) - math.log(e0)))
    return None


def fit_slope(xs, ys):
    """Least-squares slope and intercept of log y against log x."""
    lx, ly = [math.log(x) for x in xs], [math.log(y) for y in ys]
    n = len(lx)
    mx, my = sum(lx) / n, sum(ly) / n
    sxx = sum((x - mx) ** 2 for x in lx)
    b = sum((x - mx) * (y - my) for x, y in zip(lx, ly)) / sxx
    return b, my - b * mx


def load_average():
    try:
        with open("/proc/loadavg") as f:
            return [float(x) for x in f.read().split()[:3]]
    except OSError:
        return None


# ---------------------------------------------------------------- reference

def reference(scene, build, tmp, env, want_seeds=None):
    """Mean of the scene's reference seeds (an EXR in tmp), its description
    and the noise floor it leaves."""
    kind = REF_KIND[scene]
    folder = os.path.join(HERE, "references")
    spec = references.SCENES[scene]
    spp = spec["ppm_spp"] if kind == "ppm" else spec["spp"]

    def matching():
        seeds = []
        for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
            m = re.match(r"%s-sluice%s-s(\d+)\.json$" % (re.escape(scene),
                                                         "-ppm" if kind == "ppm" else ""), name)
            if not m:
                continue
            with open(os.path.join(folder, name)) as f:
                meta = json.load(f)
            if meta.get("size") == spec["size"] and meta.get("spp") == spp and \
                    os.path.exists(os.path.join(folder, name[:-5] + ".exr")):
                seeds.append((int(m.group(1)), meta))
        return sorted(seeds, key=lambda s: s[0])

    seeds = matching()
    missing = [str(i) for i in range(1, (want_seeds or REF_SEEDS[scene]) + 1) if i not in [s for s, _ in seeds]]
    if missing:
        cmd = [sys.executable, os.path.join(HERE, "references.py"), "--scenes", scene,
               "--seeds"] + missing + ["--kind", kind,
               "--exe", os.path.join(build, "apps/raytrace/sluice-raytrace"),
               "--pm-exe", os.path.join(build, "apps/photonmap/sluice-photonmap")]
        print("rendering the references: " + " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True, env=env)
        seeds = matching()
    files = [references.ref_base(folder, scene, s, kind) + ".exr" for s, _ in seeds]
    mean = os.path.join(tmp, "%s-ref.exr" % scene)
    cmd = ["oiiotool"] + files + ["--add"] * (len(files) - 1) + \
          ["--mulc", "%.17g" % (1.0 / len(files)), "-d", "float", "-o", mean]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    pair = imgdiff(build, files[0], files[1])[0] if len(files) > 1 else None
    info = {"kind": kind, "spp": spp, "seeds": [s for s, _ in seeds],
            "files": [os.path.relpath(f, ROOT) for f in files],
            "seconds": [m.get("seconds") for _, m in seeds],
            "relmse_between_seeds": pair,
            "floor": pair / (2 * len(files)) if pair is not None else None,
            "renderer": seeds[0][1].get("renderer"), "cpu": seeds[0][1].get("cpu")}
    if kind == "ppm":
        # how the photon-mapped reference compares with the path-traced one,
        # which lacks the caustic
        pt = references.ref_base(folder, scene, 1, "path") + ".exr"
        if os.path.exists(pt):
            info["relmse_against_path_traced_reference"] = imgdiff(build, mean, pt)[0]
    return mean, info


# ---------------------------------------------------------------- methods

def sluice_methods(scene, build, quick):
    rt = os.path.join(build, "apps/raytrace/sluice-raytrace")
    pm = os.path.join(build, "apps/photonmap/sluice-photonmap")
    photons = references.SCENES[scene].get("ppm_photons") or \
        {"cornell": 65000, "glassball": 5000}[scene]
    n_path = 5 if quick else 9           # 1 .. 256 spp
    n_ppm = 4 if quick else {"cornell": 7, "glassball": 9, "ring": 8}[scene]
    n_pm = 2 if quick else (4 if scene == "cornell" else 5)  # photons x 1 .. 8 or 16
    m = {"path": [[rt, "--mode", "path", "--light-samples", "1", "--max-depth", "5",
                   "--spp", str(1 << i)] for i in range(n_path)],
         "ppm": [[pm, "--progressive", "--photons", str(photons), "--spp", str(1 << i)]
                 for i in range(n_ppm)]}
    # the same images, faster (bench_photonmap.py's "fast"): the fused
    # tracer, and each kNN search to its end in one pass
    m["path-fast"] = [c + ["--exec", "fused"] for c in m["path"]]
    m["ppm-fast"] = [c + ["--exec", "fused", "--shells-per-pass", "all"] for c in m["ppm"]]
    if scene == "glassball":
        # twice the photons a pass, half the passes: the same photons for
        # half the eye passes (on glassball at 160x120 a pass's eye rays
        # cost as much as 5,000 photons: 10,000 x 16 took 1.07-1.36 s where
        # 5,000 x 32 took 1.51-1.61 s, at the same relMSE against one seed)
        m["ppm-fast-2x"] = [[pm, "--progressive", "--photons", str(2 * photons), "--spp",
                             str(1 << i), "--exec", "fused", "--shells-per-pass", "all"]
                            for i in range(n_ppm - 1)]
    for mp in (MAPS[:1] if quick else MAPS):
        for k in PM_K[scene]:
            m["pm-%s-k%d" % (mp, k)] = [[pm, "--map", mp, "--k", str(k), "--photons",
                                         str(photons << i)] for i in range(n_pm)]
    return m


def run_sluice(name, steps, common, build, ref, tmp, env, again_below=2.0):
    """Each step once (after a warm-up run), again when it took less than
    `again_below` seconds (the same seed gives the same image: only the
    time is kept, the shorter one; short renders vary most on a shared
    machine). A step the renderer refuses ends the method, its message
    recorded."""
    img, stats = os.path.join(tmp, "img.exr"), os.path.join(tmp, "s.json")
    points, refused = [], None
    try:
        render(steps[0] + common + ["--out", img, "--stats", stats], stats, env)  # warm-up
    except RuntimeError:
        pass  # the step itself reports it below
    for cmd in steps:
        args = " ".join(cmd[1:])
        try:
            t = render(cmd + common + ["--out", img, "--stats", stats], stats, env)
            if t < again_below:
                t = min(t, render(cmd + common + ["--out", img, "--stats", stats], stats, env))
        except RuntimeError as e:
            refused = {"args": args, "message": str(e)}
            print("  %-18s refused (%s): %s" % (name, args, e), flush=True)
            break
        rel, rmse = imgdiff(build, img, ref)
        points.append({"seconds": t, "relmse": rel, "rmse": rmse, "args": args})
        print("  %-18s %8.3f s  relMSE %.4g  RMSE %.4g  (%s)" % (name, t, rel, rmse, args),
              flush=True)
    return points, refused


def newest_libllvm():
    """The libLLVM with the highest version in the usual places (Dr.Jit
    takes the first it finds otherwise; with LLVM 14 and 15 its path tracer
    aborted: tools/install-mitsuba.sh)."""
    import glob
    best = None
    for p in glob.glob("/usr/lib/*-linux-gnu/libLLVM*.so*") + glob.glob("/usr/lib/llvm-*/lib/libLLVM*.so*"):
        m = re.search(r"libLLVM[-.](?:so\.)?(\d+)", os.path.basename(p))
        if m and (best is None or int(m.group(1)) > best[0]):
            best = (int(m.group(1)), p)
    return best[1] if best else None


def mitsuba_import():
    """(mitsuba module, variant) or (None, why)."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = newest_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    try:
        import mitsuba as mi
    except ImportError as e:
        return None, "no mitsuba in this Python (%s): run it with bench/.venv/bin/python" % e
    why = []
    for v in MITSUBA_VARIANTS:
        try:
            mi.set_variant(v)
            if v.startswith("llvm"):
                import drjit as dr
                x = dr.llvm.Float([1, 2]) * 2  # needs libLLVM
                dr.eval(x)
            return mi, v
        except Exception as e:  # noqa: BLE001 (any failure: try the next variant)
            why.append("%s: %s" % (v, e))
    return None, "; ".join(why)


def run_mitsuba(mi, scene, scene_exe, size, spps, build, ref, tmp, chunk=64, again_below=2.0):
    """Mitsuba 3's path tracer at each spp, timed: mi.render() until the
    image is in host memory. Past `chunk` spp the render is the mean of
    passes of `chunk` spp with other seeds (the llvm variants trace all of a
    render's samples as one wavefront, 19,200 pixels x 4,096 spp would not
    fit in memory). Warm-up renders first compile the kernels. As for
    Sluice, a render under `again_below` seconds is timed twice (the same
    seeds: the same image) and the shorter time kept."""
    import numpy as np
    xml_dir = os.path.join(tmp, scene + "-mitsuba")
    subprocess.run([scene_exe, scene, "--export-mitsuba", xml_dir], check=True,
                   stdout=subprocess.DEVNULL)
    w, h = (int(v) for v in size.split("x"))
    sc = mi.load_file(os.path.join(xml_dir, "scene.xml"), width=str(w), height=str(h),
                      max_depth=str(5 + 2), spp="1")
    img = os.path.join(tmp, "mitsuba.exr")
    for spp in sorted({min(s, chunk) for s in spps}):  # warm-up: compile
        np.array(mi.render(sc, spp=spp, seed=1000 + spp))
    points = []
    for spp in spps:
        passes = max(1, spp // chunk)
        t, again = None, False
        while t is None or (t < again_below and not again):
            again = t is not None  # a second render under again_below s: the same image
            t0 = time.perf_counter()
            acc = None
            for i in range(passes):
                arr = np.array(mi.render(sc, spp=min(spp, chunk), seed=1 + i))
                acc = arr if acc is None else acc + arr
            acc /= passes
            t = min(t, time.perf_counter() - t0) if again else time.perf_counter() - t0
        mi.util.write_bitmap(img, acc[:, :, :3], write_async=False)
        rel, rmse = imgdiff(build, img, ref)
        points.append({"seconds": t, "relmse": rel, "rmse": rmse,
                       "args": "spp %d (%d x %d)" % (spp, passes, min(spp, chunk))})
        print("  %-18s %8.3f s  relMSE %.4g  RMSE %.4g  (spp %d)" % ("mitsuba-path", t, rel,
                                                                   rmse, spp), flush=True)
    return points


def povray_version():
    try:
        out = subprocess.run(["povray", "--version"], capture_output=True, text=True)
        m = re.search(r"POV-Ray (\S+)", out.stdout + out.stderr)
        return m.group(1) if m else "unknown"
    except OSError:
        return None


def pov_seconds(log, name):
    m = re.search(r"%s Time:\s+\d+ hours\s+\d+ minutes\s+\d+ seconds \(([\d.]+) seconds\)"
                  % name, log)
    return float(m.group(1)) if m else 0.0


def run_povray(scene, scene_exe, size, steps, build, ref, tmp, again_below=2.0):
    """POV-Ray's photon mapping at growing effort: each step (photon count,
    area-light samples per side, antialiasing depth); the time is photon +
    trace time as POV-Ray reports them (parsing left out), the wall time of
    the process is recorded beside it. POV-Ray has no progressive mode: each
    step is a render of its own."""
    xml_dir = os.path.join(tmp, scene + "-mitsuba")
    if not os.path.exists(os.path.join(xml_dir, "scene.xml")):
        subprocess.run([scene_exe, scene, "--export-mitsuba", xml_dir], check=True,
                       stdout=subprocess.DEVNULL)
    w, h = (int(v) for v in size.split("x"))
    img, pov = os.path.join(tmp, "pov.exr"), os.path.join(tmp, "scene.pov")
    points = []
    for i, (n, area, aa) in enumerate([steps[0]] + list(steps)):  # the first run: warm-up
        with open(pov, "w") as f:
            f.write(pov_export.convert(os.path.join(xml_dir, "scene.xml"), photons=n,
                                       area_samples=area, width=w, height=h))
        # antialiasing: every pixel supersampled (threshold 0), method 1, jittered
        opts = ["-D", "+W%d" % w, "+H%d" % h, "+FE", "+O" + img, "+A0.0", "+AM1",
                "+R%d" % aa, "+J"]
        best = None
        for attempt in range(2):  # a render under again_below s: twice, the faster kept
            t0 = time.perf_counter()
            out = subprocess.run(["povray"] + opts + [pov], capture_output=True, text=True,
                                 env=dict(os.environ, HOME=tmp))
            wall = time.perf_counter() - t0
            if out.returncode != 0:
                raise RuntimeError("povray failed: " + out.stderr[-2000:])
            log = out.stdout + out.stderr
            t = pov_seconds(log, "Photon") + pov_seconds(log, "Trace")
            if best is None or t < best[0]:
                best = (t, wall, log)
                shutil.copyfile(img, img + ".best.exr")
            if i == 0 or t >= again_below:
                break
        if i == 0:
            continue
        t, wall, log = best
        shutil.copyfile(img + ".best.exr", img)
        stored = re.search(r"Surface photons stored:\s+(\d+)", log)
        shot = re.search(r"Number of photons shot:\s+(\d+)", log)
        spp = re.search(r"Smpls/Pxl:\s+([\d.]+)", log)
        rel, rmse = imgdiff(build, img, ref)
        points.append({"seconds": t, "wall_seconds": wall, "relmse": rel, "rmse": rmse,
                       "photon_seconds": pov_seconds(log, "Photon"),
                       "trace_seconds": pov_seconds(log, "Trace"),
                       "photons_shot": int(shot.group(1)) if shot else None,
                       "photons_stored": int(stored.group(1)) if stored else None,
                       "samples_per_pixel": float(spp.group(1)) if spp else None,
                       "args": "photons count %d, area_light %dx%d adaptive 1 jitter, "
                       "+A0.0 +AM1 +R%d +J" % (n, area, area, aa)})
        print("  %-18s %8.3f s  relMSE %.4g  RMSE %.4g  (%s; stored %s, wall %.2f s)"
              % ("povray-photons", t, rel, rmse, points[-1]["args"], points[-1]["photons_stored"],
                 wall), flush=True)
    return points


# ---------------------------------------------------------------- analysis

def analyse(res_scene):
    floor = res_scene["reference"]["floor"] or 0.0
    for name, m in res_scene["methods"].items():
        pts = [(p["seconds"], p["relmse"]) for p in m["points"]]
        m["seconds_to_relmse"] = {str(l): time_to(pts, l) for l in LEVELS}
        m["best_relmse"] = min(e for _, e in pts) if pts else None
    res_scene["ppm_slope"] = {}
    for name in ("ppm", "ppm-fast", "ppm-fast-2x"):
        ppm = res_scene["methods"].get(name)
        if not ppm or len(ppm["points"]) < 4:
            continue
        # fitted from 4 samples on (the first are dominated by the fixed
        # costs of a sample and by r_0)
        pts = [p for p in ppm["points"] if int(p["args"].split("--spp ")[1].split()[0]) >= 4]
        secs = [p["seconds"] for p in pts]
        rel = [p["relmse"] for p in pts]
        spp = [int(p["args"].split("--spp ")[1].split()[0]) for p in pts]
        st, _ = fit_slope(secs, rel)
        sn, _ = fit_slope(spp, rel)
        above = [(t, e - floor, n) for t, e, n in zip(secs, rel, spp) if e > 2 * floor]
        fit = {"points_from_spp": 4, "slope_vs_seconds": st, "slope_vs_samples": sn,
               "theory": -2.0 / 3.0}
        if len(above) >= 3:
            fit["slope_vs_seconds_floor_removed"] = fit_slope([a[0] for a in above],
                                                              [a[1] for a in above])[0]
            fit["slope_vs_samples_floor_removed"] = fit_slope([a[2] for a in above],
                                                              [a[1] for a in above])[0]
            fit["floor_removed_points"] = len(above)
        res_scene["ppm_slope"][name] = fit


def goal(res):
    """Issue 13's goal on glassball: Sluice's photon mapper reaches in 1 s
    the relMSE that Mitsuba 3's path tracer reaches in 10 s, and the
    progressive mode keeps improving past both."""
    g = res["scenes"].get("glassball")
    if not g or "mitsuba-path" not in g["methods"]:
        return None
    mpts = [(p["seconds"], p["relmse"]) for p in g["methods"]["mitsuba-path"]["points"]]
    mit10 = error_at(mpts, 10.0)
    best1, best_name = None, None
    for name, m in g["methods"].items():
        if not (name.startswith("ppm") or name.startswith("pm-")) or not m["points"]:
            continue
        e = error_at([(p["seconds"], p["relmse"]) for p in m["points"]], 1.0)
        if e is None and min(p["seconds"] for p in m["points"]) > 1.0:
            continue
        if e is None:  # every point under 1 s: the last one
            e = min(p["relmse"] for p in m["points"])
        if best1 is None or e < best1:
            best1, best_name = e, name
    ppm = g["methods"].get("ppm", {}).get("points", [])
    ppm_last = ppm[-1]["relmse"] if ppm else None
    rels = [p["relmse"] for p in ppm]
    keeps = all(b < a for a, b in zip(rels, rels[1:]))
    mit_best = min(e for _, e in mpts)
    others = [m["best_relmse"] for n, m in g["methods"].items()
              if not n.startswith("ppm") and m["best_relmse"] is not None]
    return {"mitsuba_relmse_at_10s": mit10, "mitsuba_max_seconds": max(t for t, _ in mpts),
            "sluice_pm_best_relmse_at_1s": best1, "sluice_pm_best_method_at_1s": best_name,
            "part1_holds": (mit10 is not None and best1 is not None and best1 <= mit10),
            "ppm_last_relmse": ppm_last, "ppm_last_seconds": ppm[-1]["seconds"] if ppm else None,
            "mitsuba_best_relmse": mit_best, "best_relmse_of_other_methods": min(others),
            "ppm_decreasing_every_step": keeps,
            "part2_holds": (ppm_last is not None and keeps and ppm_last < min(others)),
            "floor": g["reference"]["floor"]}


def plot(res, scene, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    g = res["scenes"][scene]
    fig, ax = plt.subplots(figsize=(7, 4.6))
    style = {"path": ("C0", "o", "-"), "ppm": ("C3", "s", "-"),
             "path-fast": ("C0", "o", "--"), "ppm-fast": ("C3", "s", "--"),
             "ppm-fast-2x": ("C1", "s", ":"),
             "mitsuba-path": ("C2", "^", "-"), "povray-photons": ("C4", "D", "-")}
    mapstyle = {"count": "-", "bitonic": "--", "stencil": ":"}
    kcol = {}
    for name, m in g["methods"].items():
        if not m["points"]:
            continue
        if name in style:
            c, mk, ls = style[name]
        else:
            _, mp, k = name.split("-")
            kcol.setdefault(k, ["C1", "C5", "C6"][len(kcol) % 3])
            c, mk, ls = kcol[k], ".", mapstyle[mp]
        ax.loglog([p["seconds"] for p in m["points"]], [p["relmse"] for p in m["points"]],
                  color=c, marker=mk, linestyle=ls, label=name, markersize=4, linewidth=1.2)
    if g["reference"]["floor"]:
        ax.axhline(g["reference"]["floor"], color="grey", linestyle="-.", linewidth=0.8,
                   label="reference noise floor")
    ax.set_xlabel("seconds (render only)")
    ax.set_ylabel("relMSE against the reference")
    la = res.get("load_average_at_start")
    ppm_ref = g["reference"]["kind"] == "ppm"
    ax.set_title("%s %s, reference: %s %d %s x %d seeds\n%s, %d cores, load %s at the start, %s"
                 % (scene, g["size"], "PPM" if ppm_ref else "path traced",
                    g["reference"]["spp"], "samples" if ppm_ref else "spp", len(g["reference"]["seeds"]), res["cpu"],
                    res["cores"], "%.1f" % la[0] if la else "?", res["date"][:10]), fontsize=8)
    ax.grid(True, which="major", linewidth=0.4, alpha=0.5)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return True


def fmt_t(v):
    return "%.3g" % v if v is not None else "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", action="append", choices=SCENES,
                    help="scene (repeatable; default all three)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default=os.path.join(ROOT, "bench/results/error.json"))
    ap.add_argument("--plots", default=None,
                    help="folder for error-SCENE.png (default: the --out file's folder)")
    ap.add_argument("--quick", action="store_true", help="fewer, cheaper steps")
    ap.add_argument("--ref-seeds", type=int,
                    help="render reference seeds 1 .. N where missing (default: per scene, "
                    "glassball 8, else 2; every matching seed there is averaged)")
    ap.add_argument("--no-mitsuba", action="store_true")
    ap.add_argument("--no-povray", action="store_true")
    ap.add_argument("--povray-scene", action="append", choices=SCENES,
                    help="scenes POV-Ray renders (default glassball)")
    a = ap.parse_args()
    load = load_average()
    scenes = a.scene or SCENES
    build = os.path.abspath(a.build)
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(build, "pocl-cache"))
    scene_exe = os.path.join(build, "apps/common/sluice-scene")
    res = {"cpu": references.cpu_model(), "cores": os.cpu_count(),
           "load_average_at_start": load, "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
           "commit": references.git_commit(),
           "command": " ".join([os.path.relpath(sys.executable, ROOT)
                                if sys.executable.startswith(ROOT) else "python3"] + sys.argv),
           "levels": LEVELS, "metric": "sluice-imgdiff relmse: mean of (a - b)^2 / (b^2 + 0.01)",
           "peers": {}, "scenes": {}}
    mi = None
    if not a.no_mitsuba:
        mi, variant = mitsuba_import()
        if mi:
            res["peers"]["mitsuba"] = {"version": mi.__version__, "variant": variant,
                                       "libllvm": os.environ.get("DRJIT_LIBLLVM_PATH")}
        else:
            res["peers"]["mitsuba"] = {"skipped": variant}
            print("Mitsuba left out: " + variant, flush=True)
    pov = None if a.no_povray else povray_version()
    res["peers"]["povray"] = {"version": pov} if pov else \
        {"skipped": "--no-povray" if a.no_povray else "povray not installed"}
    print("%s, %d cores, load average %s at the start" % (res["cpu"], res["cores"], load),
          flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            size = references.SCENES[scene]["size"]
            ref, rinfo = reference(scene, build, tmp, env, a.ref_seeds)
            print("%s %s: reference %s x %d seeds, floor %s" %
                  (scene, size, rinfo["kind"], len(rinfo["seeds"]), rinfo["floor"]), flush=True)
            g = {"size": size, "reference": rinfo, "methods": {}}
            # a seed no reference uses: the same seed would give a method
            # the reference's own first samples (the same renderer, the same
            # keys), and errors measured against a reference that shares
            # them come out too low
            common = ["--scene", scene, "--size", size, "--quiet", "--no-profile",
                      "--seed", str(METHOD_SEED)]
            for name, steps in sluice_methods(scene, build, a.quick).items():
                pts, refused = run_sluice(name, steps, common, build, ref, tmp, env)
                g["methods"][name] = {"points": pts}
                if refused:
                    g["methods"][name]["refused"] = refused
            if mi:
                n = 5 if a.quick else {"cornell": 11, "glassball": 14, "ring": 11}[scene]
                g["methods"]["mitsuba-path"] = {"points": run_mitsuba(
                    mi, scene, scene_exe, size, [1 << i for i in range(n)], build, ref, tmp)}
            if pov and scene in (a.povray_scene or POVRAY_SCENES):
                g["methods"]["povray-photons"] = {"points": run_povray(
                    scene, scene_exe, size, POVRAY_STEPS[:2] if a.quick else POVRAY_STEPS,
                    build, ref, tmp)}
            analyse(g)
            res["scenes"][scene] = g
            # written after every scene: a long run that fails keeps what it had
            with open(a.out, "w") as f:
                json.dump(res, f, indent=1)
                f.write("\n")
    res["goal_glassball"] = goal(res)
    res["load_average_at_end"] = load_average()
    with open(a.out, "w") as f:
        json.dump(res, f, indent=1)
        f.write("\n")
    plots = a.plots or os.path.dirname(os.path.abspath(a.out))
    for scene, g in res["scenes"].items():
        print("\nseconds to reach relMSE (%s %s; reference floor %s; %s):" %
              (scene, g["size"], g["reference"]["floor"], res["cpu"]))
        print("%-18s" % "method" + "".join("%9g" % l for l in LEVELS) + "   best relMSE")
        for name, m in g["methods"].items():
            print("%-18s" % name + "".join("%9s" % fmt_t(m["seconds_to_relmse"][str(l)])
                                           for l in LEVELS) + "   %s" % fmt_t(m["best_relmse"])
                  + ("   (refused: %s)" % m["refused"]["args"] if "refused" in m else ""))
        for name, s in g.get("ppm_slope", {}).items():
            print("%s slope of log relMSE: %.3f against log seconds, %.3f against log samples"
                  " (theory -2/3)%s" % (name, s["slope_vs_seconds"], s["slope_vs_samples"],
                                        "; floor removed: %.3f / %.3f" %
                                        (s["slope_vs_seconds_floor_removed"],
                                         s["slope_vs_samples_floor_removed"])
                                        if "slope_vs_seconds_floor_removed" in s else ""))
        path = os.path.join(plots, "error-%s.png" % scene)
        if plot(res, scene, path):
            print("plot: %s" % os.path.relpath(path, ROOT))
        else:
            print("(no matplotlib: no plot)")
    if res["goal_glassball"]:
        print("\ngoal (glassball):", json.dumps(res["goal_glassball"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
