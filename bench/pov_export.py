#!/usr/bin/env python3
"""Converts a scene exported by `sluice-scene SCENE --export-mitsuba DIR`
(DIR/scene.xml and its binary PLY meshes) into a POV-Ray 3.7 scene with
photon-mapped caustics, for bench/bench_error.py's POV-Ray peer.

  bench/pov_export.py DIR/scene.xml OUT.pov [--photons N] [--area-samples N]

What it maps, and how (Sluice's units are radiometric; POV-Ray's are not):
  camera     perspective, at the same eye and target; POV-Ray's `angle` is
             the horizontal field of view, from the vertical one and the
             aspect; `right -x` because POV-Ray is left-handed and Sluice
             right-handed (the image is otherwise mirrored).
  diffuse    pigment = albedo, `diffuse 1`, no ambient, specular or phong:
             POV-Ray's diffuse term is pigment * light colour * attenuation
             * cos, without the 1/pi of a Lambertian BRDF, so the light
             colours below carry the 1/pi.
  glass      `rgbf 1` with exact Fresnel reflection (`reflection {0, 1
             fresnel on}`, `conserve_energy`), `interior { ior }`, a photon
             target for reflection and refraction. A mesh needs
             `inside_vector` to have an inside.
  mirror     `reflection { rgb R }`, no diffuse, a photon target.
  point      radiant intensity I: inverse-square falloff is POV-Ray's
             `fade_power 2`, whose attenuation is 2 / (1 + (d / f)^2); with
             a tiny fade distance f that is 2 f^2 / d^2 to 1e-6, so the
             colour is I / (2 pi f^2) (the pi: see diffuse).
  area       a one-sided emitting parallelogram (two triangles) of radiance L
             and area A radiates L A cos(theta) in the direction theta from
             its normal. POV-Ray has no such emitter: an `area_light`
             (N x N jittered point lights spread over the parallelogram)
             made a spotlight pointing along the normal with `radius 90
             falloff 90 tightness 1`, whose intensity is cos(theta)^1 and
             nothing behind it, colour L A / (2 pi f^2) as for a point
             light; photons are shot from the whole area (`photons {
             area_light }`). The emitting surface itself, which the camera
             sees in the glass, is the light's `looks_like`: a mesh of
             `emission` L that casts no shadow.
What it does not: POV-Ray's photons are caustic photons only (paths through
a specular photon target before their diffuse hit); diffuse interreflection
would need its radiosity, which is left off, so light that bounces off one
diffuse surface onto another is missing (in glassball: the floor lighting
the ball and the floor again through it, a small term).
"""
import argparse
import math
import os
import re
import struct
import sys
import xml.etree.ElementTree as ET

FADE = 1e-3  # fade distance: attenuation 2 f^2 / d^2 to within (f / d)^2


def read_ply(path):
    """Binary little-endian PLY as sluice-scene writes it: float x y z
    [nx ny nz] vertices, uchar-int triangle lists."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv = nf = 0
    props = []
    for line in header:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
        elif w[:2] == ["property", "float"]:
            props.append(w[2])
        elif line.startswith("format") and "binary_little_endian" not in line:
            raise ValueError("%s: only binary little-endian PLY" % path)
    stride = 4 * len(props)
    verts, normals = [], []
    has_n = "nx" in props
    off = end
    for i in range(nv):
        v = struct.unpack_from("<%df" % len(props), data, off + i * stride)
        verts.append(v[0:3])
        if has_n:
            normals.append(v[3:6])
    off += nv * stride
    faces = []
    for i in range(nf):
        n = data[off]
        if n != 3:
            raise ValueError("%s: face %d has %d vertices" % (path, i, n))
        faces.append(struct.unpack_from("<3i", data, off + 1))
        off += 13
    return verts, (normals if has_n else None), faces


def floats(s):
    return [float(x) for x in s.replace(",", " ").split()]


def vec(v):
    return "<%.9g, %.9g, %.9g>" % tuple(v)


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    return math.sqrt(sum(x * x for x in a))


def mesh2(verts, normals, faces, inside=False):
    out = ["mesh2 {", "  vertex_vectors { %d," % len(verts)]
    out.append(",\n".join("    " + vec(v) for v in verts))
    out.append("  }")
    if normals:
        out.append("  normal_vectors { %d," % len(normals))
        out.append(",\n".join("    " + vec(n) for n in normals))
        out.append("  }")
    out.append("  face_indices { %d," % len(faces))
    out.append(",\n".join("    <%d, %d, %d>" % f for f in faces))
    out.append("  }")
    if inside:
        out.append("  inside_vector <0, 0, 1>")
    return "\n".join(out)


def bsdf_texture(b):
    """(texture text, photon block, interior, is_specular) of a Mitsuba BSDF
    element as sluice-scene writes them."""
    if b.get("type") == "twosided":
        b = b.find("bsdf")
    t = b.get("type")
    vals = {e.get("name"): e.get("value") for e in b}
    if t == "diffuse":
        a = floats(vals.get("reflectance", "0.5"))
        return ("texture { pigment { rgb %s } finish { ambient 0 emission 0 diffuse 1 "
                "specular 0 phong 0 } }" % vec(a), "", "", False)
    if t == "dielectric":
        ior = float(vals.get("int_ior", "1.5")) / float(vals.get("ext_ior", "1"))
        return ("texture { pigment { rgbf <1, 1, 1, 1> } finish { ambient 0 emission 0 "
                "diffuse 0 specular 0 phong 0 reflection { 0, 1 fresnel on } "
                "conserve_energy } }",
                "photons { target reflection on refraction on collect off }",
                "interior { ior %.9g }" % ior, True)
    if t == "conductor":
        r = floats(vals.get("specular_reflectance", "1"))
        return ("texture { pigment { rgb 0 } finish { ambient 0 emission 0 diffuse 0 "
                "specular 0 phong 0 reflection { rgb %s } } }" % vec(r),
                "photons { target reflection on refraction off collect off }", "", True)
    raise ValueError("unsupported BSDF type %r" % t)


def convert(xml_path, photons=20000, area_samples=8, width=None, height=None,
            max_trace_level=None, gather=(20, 100)):
    """The POV-Ray scene text for the Mitsuba export at xml_path."""
    with open(xml_path) as f:
        # sluice-scene's header comment names "--export-mitsuba": a "--" inside
        # a comment is not well-formed XML (Mitsuba's parser lets it pass)
        text = re.sub(r"<!--.*?-->", "", f.read(), flags=re.S)
    root = ET.fromstring(text)
    base = os.path.dirname(os.path.abspath(xml_path))
    defaults = {d.get("name"): d.get("value") for d in root.findall("default")}
    w = int(width or defaults.get("width", 512))
    h = int(height or defaults.get("height", 512))
    depth = int(max_trace_level or defaults.get("max_depth", 7))
    bsdfs = {b.get("id"): b for b in root.findall("bsdf")}
    out = ["// Written by bench/pov_export.py from %s" % os.path.relpath(xml_path),
           "#version 3.7;",
           "global_settings {",
           "  assumed_gamma 1.0",
           "  ambient_light 0",
           "  max_trace_level %d" % depth,
           "  adc_bailout 0",
           "  photons { count %d autostop 0 jitter 0.4 max_trace_level %d gather %d, %d }"
           % (photons, depth, gather[0], gather[1]),
           "}",
           "background { rgb 0 }"]
    sensor = root.find("sensor")
    fov = float(sensor.find("float[@name='fov']").get("value"))
    la = sensor.find("transform/lookat")
    eye, tgt, up = floats(la.get("origin")), floats(la.get("target")), floats(la.get("up"))
    aspect = w / h
    hfov = 2 * math.degrees(math.atan(math.tan(math.radians(fov) / 2) * aspect))
    out.append("camera { perspective location %s sky %s look_at %s right -x * %.9g up y "
               "angle %.9g }" % (vec(eye), vec(up), vec(tgt), aspect, hfov))
    for e in root.findall("emitter"):
        if e.get("type") != "point":
            raise ValueError("unsupported emitter %r" % e.get("type"))
        p = e.find("point")
        pos = [float(p.get(k)) for k in "xyz"]
        inten = floats(e.find("rgb[@name='intensity']").get("value"))
        col = [i / (2 * math.pi * FADE * FADE) for i in inten]
        out.append("light_source { %s color rgb %s fade_distance %g fade_power 2 "
                   "photons { reflection on refraction on } }" % (vec(pos), vec(col), FADE))
    for s in root.findall("shape"):
        fn = s.find("string[@name='filename']").get("value")
        verts, normals, faces = read_ply(os.path.join(base, fn))
        face_normals = s.find("boolean[@name='face_normals']")
        if face_normals is not None and face_normals.get("value") == "true":
            normals = None
        em = s.find("emitter")
        bsdf = bsdfs[s.find("ref").get("id")]
        if em is not None:
            if em.get("type") != "area" or len(faces) != 2 or len(verts) != 4:
                raise ValueError("%s: only a parallelogram (two triangles) can be an area light"
                                 % fn)
            L = floats(em.find("rgb[@name='radiance']").get("value"))
            a, b, c = (verts[i] for i in faces[0])
            n = cross(sub(b, a), sub(c, a))  # counter-clockwise front: the emitting side
            area = sum(0.5 * norm(cross(sub(verts[f[1]], verts[f[0]]),
                                        sub(verts[f[2]], verts[f[0]]))) for f in faces)
            nn = [x / norm(n) for x in n]
            centre = [sum(v[i] for v in verts) / 4 for i in range(3)]
            # the two sides of the parallelogram from one corner
            corner = verts[0]
            others = sorted(verts[1:], key=lambda v: norm(sub(v, corner)))
            u, v = sub(others[0], corner), sub(others[1], corner)
            col = [l * area / (2 * math.pi * FADE * FADE) for l in L]
            out.append("light_source {\n  %s color rgb %s\n  spotlight point_at %s radius 90 "
                       "falloff 90 tightness 1\n  area_light %s, %s, %d, %d adaptive 1 jitter\n"
                       "  fade_distance %g fade_power 2\n"
                       "  photons { reflection on refraction on area_light }\n"
                       "  looks_like { %s\n    texture { pigment { rgb %s } finish { ambient 0 "
                       "diffuse 0 emission 1 } } no_shadow }\n}"
                       % (vec(centre), vec(col), vec([centre[i] + nn[i] for i in range(3)]),
                          vec(u), vec(v), area_samples, area_samples, FADE,
                          mesh2([sub(p, centre) for p in verts], None, faces) + "\n  }",
                          vec(L)))
            continue
        tex, ph, interior, specular = bsdf_texture(bsdf)
        out.append(mesh2(verts, normals, faces, inside=bool(interior)) + "\n  %s\n  %s\n  %s\n}"
                   % (tex, interior, ph))
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("xml")
    ap.add_argument("out")
    ap.add_argument("--photons", type=int, default=20000, help="photons { count } (20000)")
    ap.add_argument("--area-samples", type=int, default=8,
                    help="point lights per side of an area light (8)")
    ap.add_argument("--size", help="WxH (default: the export's)")
    a = ap.parse_args()
    w = h = None
    if a.size:
        w, h = (int(x) for x in a.size.split("x"))
    with open(a.out, "w") as f:
        f.write(convert(a.xml, a.photons, a.area_samples, w, h))
    return 0


if __name__ == "__main__":
    sys.exit(main())
