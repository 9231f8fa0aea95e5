#!/usr/bin/env python3
"""Compares Sluice's converged path-traced references (bench/references.py)
with Mitsuba 3 renders of the same scenes, and checks both against an
analytic case. Run it with the Python of bench/.venv (tools/install-mitsuba.sh
makes it): Mitsuba 3 (variant scalar_rgb) renders, numpy measures.

For each scene:
  1. sluice-scene SCENE --export-mitsuba bench/references/SCENE-mitsuba/
     writes scene.xml and PLY meshes (Sluice's conventions: linear RGB
     radiance, one-sided area emitters, two-sided BSDFs, vertical fov, box
     filter, Mitsuba max_depth = Sluice max depth + 2);
  2. Mitsuba renders it at the references' size and max depth, once per seed
     (bench/references/SCENE-mitsuba-s<seed>.exr and .json; cached);
  3. the renders are compared (luminance Y for the regions):
       relMSE(A, B) = mean over pixels and channels of (A - B)^2 /
                (((A + B) / 2)^2 + (0.1 m)^2), m the image's mean (a floor for
                dark pixels);
       cross = relMSE between a Sluice and a Mitsuba render, averaged over
                the 4 seed pairs; same = relMSE between the two seeds of one
                renderer, averaged over both renderers. Without bias both
                estimate the same noise (sigma_S^2 + sigma_M^2, relative), so
                ratio = cross / same is about 1; a bias adds to cross only.
                Its spread (sigma) comes from resampling 8 x 8 blocks.
       regions: the image cut into 8 x 8 blocks; per block the mean luminance
                of the two-seed means S and M, their ratio and z = (S - M) /
                standard error, from the seeds' per-pixel differences.
     A scene agrees when ratio - 1 <= max(3 sigma, 0.05) and every block with
     at least 1% of the image's mean luminance has |z| <= 4.
The analytic case (bench/scenes/quadlight.json) renders a diffuse floor
under a square light with both renderers and compares the floor's radiance
under the light's centre with the closed form (point-to-parallel-rectangle
form factor). Results go to bench/references/agreement.json.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

from references import cpu_model

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
VARIANT = "scalar_rgb"


def mitsuba():
    import mitsuba as mi
    mi.set_variant(VARIANT)
    return mi


def read_exr(path):
    mi = mitsuba()
    a = np.array(mi.Bitmap(path), dtype=np.float64)
    return a[:, :, :3]


def export(scene_exe, scene, out_dir):
    subprocess.run([scene_exe, scene, "--export-mitsuba", out_dir], check=True,
                   stdout=subprocess.DEVNULL)
    return os.path.join(out_dir, "scene.xml")


def render_mitsuba(xml, path, width, height, spp, max_depth, seed, force):
    """Renders xml to path (EXR) with a JSON beside it; cached."""
    meta_path = path[:-4] + ".json"
    want = {"width": width, "height": height, "spp": spp, "max_depth": max_depth,
            "seed": seed, "variant": VARIANT}
    if not force and os.path.exists(path) and os.path.exists(meta_path):
        with open(meta_path) as f:
            have = json.load(f)
        if all(have.get(k) == v for k, v in want.items()):
            return have
    mi = mitsuba()
    t0 = time.time()
    sc = mi.load_file(xml, spp=str(spp), width=str(width), height=str(height),
                      max_depth=str(max_depth), seed=str(seed))
    img = mi.render(sc, seed=seed)
    mi.util.write_bitmap(path, img, write_async=False)
    meta = dict(want)
    meta.update({"renderer": "mitsuba %s %s path" % (mi.__version__, VARIANT),
                 "seconds": round(time.time() - t0, 1), "cpu": cpu_model(),
                 "cores": os.cpu_count(), "xml": os.path.relpath(xml, ROOT)})
    with open(meta_path, "w") as f:
        json.dump(meta, f, indent=2)
        f.write("\n")
    return meta


def luminance(a):
    return 0.2126 * a[:, :, 0] + 0.7152 * a[:, :, 1] + 0.0722 * a[:, :, 2]


def rel_map(a, b, m):
    """Per-pixel relative squared error, averaged over the channels."""
    return np.mean((a - b) ** 2 / (((a + b) / 2) ** 2 + (0.1 * m) ** 2), axis=2)


def compare(s1, s2, m1, m2, blocks=8, resamples=1000):
    ls1, ls2, lm1, lm2 = (luminance(a) for a in (s1, s2, m1, m2))
    mean = float(np.mean((lm1 + lm2) / 2))
    # relMSE per pixel between renders of different renderers (4 seed pairs)
    # and of the same renderer (2 pairs): with no bias both estimate
    # sigma_S^2 + sigma_M^2 (relative), so their ratio is about 1.
    cross = sum(rel_map(a, b, mean) for a in (s1, s2) for b in (m1, m2)) / 4
    same = (rel_map(s1, s2, mean) + rel_map(m1, m2, mean)) / 2
    h, w = ls1.shape
    cells = [(slice(by * h // blocks, (by + 1) * h // blocks),
              slice(bx * w // blocks, (bx + 1) * w // blocks))
             for by in range(blocks) for bx in range(blocks)]
    bc = np.array([cross[ys, xs].sum() for ys, xs in cells])
    bs = np.array([same[ys, xs].sum() for ys, xs in cells])
    ratio = float(bc.sum() / bs.sum())
    # the ratio's spread: resampling the blocks (bootstrap, fixed seed)
    rng = np.random.default_rng(13)
    picks = rng.integers(0, len(cells), size=(resamples, len(cells)))
    boot = bc[picks].sum(axis=1) / bs[picks].sum(axis=1)
    sigma = float(np.std(boot))
    ls, lm = (ls1 + ls2) / 2, (lm1 + lm2) / 2
    # per-pixel variance of each two-seed mean: (X1 - X2)^2 / 4
    vs = (ls1 - ls2) ** 2 / 4
    vm = (lm1 - lm2) ** 2 / 4
    regions = []
    for (ys, xs), bxy in zip(cells, [(bx, by) for by in range(blocks) for bx in range(blocks)]):
        n = ls[ys, xs].size
        ms, mm = float(ls[ys, xs].mean()), float(lm[ys, xs].mean())
        se = math.sqrt(float(vs[ys, xs].sum() + vm[ys, xs].sum())) / n
        z = (ms - mm) / se if se > 0 else (0.0 if ms == mm else math.inf)
        regions.append({"block": list(bxy), "sluice": ms, "mitsuba": mm,
                        "ratio": ms / mm if mm > 0 else None, "z": z,
                        "lit": mm >= 0.01 * mean})
    lit = [g for g in regions if g["lit"]]
    gs, gm = float(ls.mean()), float(lm.mean())
    gse = math.sqrt(float(vs.sum() + vm.sum())) / ls.size
    worst = max(lit, key=lambda g: abs(g["z"]))
    ok = ratio - 1 <= max(3 * sigma, 0.05) and all(abs(g["z"]) <= 4 for g in lit)
    return {"relmse_cross": float(cross.mean()), "relmse_same": float(same.mean()),
            "ratio": ratio, "ratio_sigma": sigma,
            "relmse_sluice_seeds": float(rel_map(s1, s2, mean).mean()),
            "relmse_mitsuba_seeds": float(rel_map(m1, m2, mean).mean()),
            "mean_sluice": gs, "mean_mitsuba": gm, "mean_ratio": gs / gm,
            "mean_z": (gs - gm) / gse if gse > 0 else 0.0,
            "blocks_lit": len(lit),
            "block_ratio_min": min(g["ratio"] for g in lit),
            "block_ratio_max": max(g["ratio"] for g in lit),
            "block_z_max": abs(worst["z"]), "worst_block": worst,
            "blocks_beyond_z4": sum(abs(g["z"]) > 4 for g in lit),
            "agree": ok, "regions": regions}


def quad_form_factor(x, y):
    """Form factor from a point to a parallel x by y rectangle (in units of
    the height) with a corner straight above it."""
    ax, ay = math.sqrt(1 + x * x), math.sqrt(1 + y * y)
    return (x / ax * math.atan(y / ax) + y / ay * math.atan(x / ay)) / (2 * math.pi)


def analytic(args, out):
    """The floor's radiance under the centre of the square light, analytic
    and rendered by both (direct light only: max depth 0 / Mitsuba 2)."""
    scene = os.path.join(HERE, "scenes", "quadlight.json")
    expect = 0.5 / math.pi * 10.0 * math.pi * 4 * quad_form_factor(0.5, 0.5)
    size, spp = 64, args.analytic_spp
    base = os.path.join(out, "quadlight")
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(ROOT, "build", "pocl-cache"))
    subprocess.run([args.raytrace, "--scene", scene, "--mode", "path", "--spp", str(spp),
                    "--max-depth", "0", "--out", base + "-sluice.exr", "--quiet"],
                   check=True, env=env)
    xml = export(args.scene_exe, scene, base + "-mitsuba")
    render_mitsuba(xml, base + "-mitsuba.exr", size, size, spp, 2, 0, True)
    res = {"expected": expect}
    c = slice(size // 2 - 4, size // 2 + 4)
    for name in ("sluice", "mitsuba"):
        img = read_exr("%s-%s.exr" % (base, name))
        centre = img[c, c, :]
        mean = float(centre.mean())
        se = float(centre.std() / math.sqrt(centre.size))
        res[name] = {"centre_8x8": mean, "stderr": se, "ratio": mean / expect}
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--refs", default=os.path.join(HERE, "references"),
                    help="folder of the Sluice references and outputs (default bench/references)")
    ap.add_argument("--scene-exe", default=os.path.join(ROOT, "build/apps/common/sluice-scene"),
                    help="sluice-scene executable")
    ap.add_argument("--raytrace", default=os.path.join(ROOT, "build/apps/raytrace/sluice-raytrace"),
                    help="sluice-raytrace executable (for the analytic case)")
    ap.add_argument("--scenes", nargs="+", default=["cornell", "glassball", "ring"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2],
                    help="seeds of the Sluice references and of the Mitsuba renders")
    ap.add_argument("--spp", type=int, help="Mitsuba's samples per pixel (default: the references')")
    ap.add_argument("--analytic-spp", type=int, default=256,
                    help="samples per pixel of the analytic case (default 256)")
    ap.add_argument("--no-analytic", action="store_true", help="skip the analytic case")
    ap.add_argument("--force", action="store_true", help="render Mitsuba even when cached")
    args = ap.parse_args()
    if len(args.seeds) != 2:
        ap.error("two seeds are needed to measure the noise")

    report = {"cpu": cpu_model(), "cores": os.cpu_count(), "scenes": {}}
    for scene in args.scenes:
        metas, sl = [], []
        for seed in args.seeds:
            base = os.path.join(args.refs, "%s-sluice-s%d" % (scene, seed))
            if not os.path.exists(base + ".json"):
                sys.exit("%s.json missing: run bench/references.py first" % base)
            with open(base + ".json") as f:
                metas.append(json.load(f))
            sl.append(read_exr(base + ".exr"))
        w, h = (int(v) for v in metas[0]["size"].split("x"))
        depth = metas[0]["max_depth"] + 2
        spp = args.spp or metas[0]["spp"]
        xml = export(args.scene_exe, scene, os.path.join(args.refs, scene + "-mitsuba"))
        mm, mt = [], []
        for seed in args.seeds:
            path = os.path.join(args.refs, "%s-mitsuba-s%d.exr" % (scene, seed))
            mt.append(render_mitsuba(xml, path, w, h, spp, depth, seed, args.force))
            mm.append(read_exr(path))
        res = compare(sl[0], sl[1], mm[0], mm[1])
        res.update({"size": "%dx%d" % (w, h), "sluice_spp": metas[0]["spp"],
                    "sluice_seconds": [m["seconds"] for m in metas],
                    "mitsuba_spp": spp, "mitsuba_max_depth": depth,
                    "mitsuba_seconds": [m["seconds"] for m in mt]})
        report["scenes"][scene] = res
        print("%-10s relMSE S-M %.3g  same %.3g  ratio %.3f +- %.3f  mean S/M %.4f (z %.1f)  "
              "blocks S/M %.3f..%.3f, max |z| %.1f  %s" %
              (scene, res["relmse_cross"], res["relmse_same"], res["ratio"], res["ratio_sigma"],
               res["mean_ratio"],
               res["mean_z"], res["block_ratio_min"], res["block_ratio_max"],
               res["block_z_max"], "agree" if res["agree"] else "DISAGREE"), flush=True)
    if not args.no_analytic:
        a = analytic(args, args.refs)
        report["analytic_quadlight"] = a
        print("quadlight  expected %.5f  sluice %.5f (+-%.5f, ratio %.4f)  "
              "mitsuba %.5f (+-%.5f, ratio %.4f)" %
              (a["expected"], a["sluice"]["centre_8x8"], a["sluice"]["stderr"],
               a["sluice"]["ratio"], a["mitsuba"]["centre_8x8"], a["mitsuba"]["stderr"],
               a["mitsuba"]["ratio"]))
    with open(os.path.join(args.refs, "agreement.json"), "w") as f:
        json.dump(report, f, indent=2)
        f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
