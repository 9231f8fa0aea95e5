#!/usr/bin/env python3
"""Self-test of bench/bench_error.py's arithmetic and of bench/pov_export.py,
run by the test suite (bench_error_selftest). It needs no Mitsuba, POV-Ray,
numpy or matplotlib: only the standard library and sluice-scene.

  bench/test_bench_error.py SLUICE_SCENE_EXE"""
import math
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_error  # noqa: E402
import pov_export  # noqa: E402


def close(a, b, tol=1e-9):
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))


def main():
    fails, done = [], []

    def check(cond, what):
        print("%s %s" % ("ok  " if cond else "FAIL", what))
        done.append(what)
        if not cond:
            fails.append(what)

    pts = [(1.0, 0.1), (4.0, 0.025), (16.0, 0.00625)]  # relMSE ~ 1/t
    check(close(bench_error.time_to(pts, 0.05), 2.0), "time_to interpolates in log-log")
    check(bench_error.time_to(pts, 1.0) == 1.0, "time_to: a level above the first point")
    check(bench_error.time_to(pts, 1e-3) is None, "time_to: a level never reached")
    check(close(bench_error.error_at(pts, 8.0), 0.0125), "error_at interpolates in log-log")
    check(bench_error.error_at(pts, 20.0) is None, "error_at: outside the points")
    b, a = bench_error.fit_slope([1, 2, 4, 8], [3 * x ** (-2 / 3) for x in [1, 2, 4, 8]])
    check(close(b, -2 / 3) and close(math.exp(a), 3.0), "fit_slope of a power law")

    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.argv[1], "glassball", "--export-mitsuba", tmp], check=True,
                       stdout=subprocess.DEVNULL)
        pov = pov_export.convert(os.path.join(tmp, "scene.xml"), photons=1234, area_samples=5,
                                 width=160, height=120)
        check("photons { count 1234" in pov, "global photons block")
        check("right -x * 1.33333333" in pov, "camera mirrored for POV-Ray's left-handedness")
        hfov = 2 * math.degrees(math.atan(math.tan(math.radians(20)) * 4 / 3))
        m = re.search(r"angle ([\d.]+)", pov)
        check(m and close(float(m.group(1)), hfov, 1e-6), "horizontal fov from the vertical 40")
        check("vertex_vectors { 2562," in pov and "face_indices { 5120," in pov and
              "normal_vectors { 2562," in pov, "the ball as a smooth mesh2")
        check("inside_vector" in pov and "interior { ior 1.5 }" in pov, "the ball is solid glass")
        m = re.search(r"light_source \{\n  (<[^>]*>) color rgb <([\d.e+]+),", pov)
        want = 25 * 0.36 / (2 * math.pi * pov_export.FADE ** 2)
        check(m and close(float(m.group(2)), want, 1e-6), "area light colour L A / (2 pi f^2)")
        check(m and m.group(1) == "<-0.5, 3, 0.500000007>", "area light at the quad's centre")
        check("point_at <-0.5, 2, 0.500000007>" in pov, "area light facing down (its front)")
        check("area_light <0, 0, 0.600000009>, <0.600000024, 0, 0>, 5, 5" in pov,
              "area light's sides and samples")
    print("%d passed, %d failed" % (len(done) - len(fails), len(fails)))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
