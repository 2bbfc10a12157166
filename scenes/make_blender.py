#!/usr/bin/env python3
"""Writes blender.obj and blender.mtl: a small room as Blender 4.x's OBJ
exporter writes it (Y up, forward -Z), so that the loader is tested on the
files users bring: several `o` objects, `v/vt/vn` faces with indices running
on across objects, `s 0` / `s off` / `s 1`, quads, triangles and n-gons
(an octagonal lamp, hexagonal pedestal caps), and an MTL with every
statement Blender writes (Ns, Ka, Kd, Ks, Ke, Ni, d, illum).

    python3 scenes/make_blender.py      (from the repository's top)
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))

# name: (Kd, Ke). Blender's Principled BSDF base colour 0.8 is the
# default; the lamp's Ke is its emission colour times strength.
MATERIALS = [
    ("Wall", (0.8, 0.8, 0.8), (0, 0, 0)),
    ("Floor", (0.6, 0.45, 0.3), (0, 0, 0)),
    ("RedPaint", (0.7, 0.1, 0.08), (0, 0, 0)),
    ("BluePaint", (0.1, 0.2, 0.7), (0, 0, 0)),
    ("Emission", (0.8, 0.8, 0.8), (8.0, 7.2, 6.0)),
]


def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def normal(poly):
    n = (0.0, 0.0, 0.0)
    for i in range(len(poly)):  # Newell's method: any planar polygon
        c = cross(poly[i], poly[(i + 1) % len(poly)])
        n = (n[0] + c[0], n[1] + c[1], n[2] + c[2])
    l = math.sqrt(sum(x * x for x in n))
    return tuple(x / l for x in n)


def box(lo, hi, inward=False):
    """Six quads, counter-clockwise seen from outside (inside if inward)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = [
        [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],  # bottom, -y
        [(x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)],  # top, +y
        [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],  # front, +z
        [(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)],  # back, -z
        [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],  # left, -x
        [(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)],  # right, +x
    ]
    return [f[::-1] for f in faces] if inward else faces


def prism(center, radius, y0, y1, sides, phase=0.0):
    """A vertical prism: two n-gon caps and `sides` quads, outward."""
    ring = [(center[0] + radius * math.cos(phase + 2 * math.pi * k / sides),
             center[1] + radius * math.sin(phase + 2 * math.pi * k / sides)) for k in range(sides)]
    bottom = [(x, y0, z) for x, z in ring]
    top = [(x, y1, z) for x, z in ring]
    faces = [bottom, top[::-1]]  # bottom seen from below, top from above
    for k in range(sides):
        j = (k + 1) % sides
        faces.append([bottom[k], top[k], top[j], bottom[j]][::-1])
    return faces


def fix(faces):
    """Orient every face so that its normal points away from the solid's
    centroid: prism() builds rings in x-z, whose handedness flips."""
    c = [sum(v[i] for f in faces for v in f) / sum(len(f) for f in faces) for i in range(3)]
    out = []
    for f in faces:
        n = normal(f)
        m = [sum(v[i] for v in f) / len(f) for i in range(3)]
        out.append(f if sum(n[i] * (m[i] - c[i]) for i in range(3)) > 0 else f[::-1])
    return out


def objects():
    room = box((-2, 0, -2), (2, 2.5, 2), inward=True)
    # (object, smoothing statement, [(material, faces)])
    return [
        ("Room", "s 0", [("Floor", room[:1]), ("Wall", room[1:4]), ("RedPaint", room[4:5]),
                         ("BluePaint", room[5:])]),
        # The lamp: an octagon 1 cm under the ceiling, facing down.
        ("Lamp", "s 0", [("Emission", [[(0.5 * math.cos(2 * math.pi * k / 8), 2.49,
                                        0.5 * math.sin(2 * math.pi * k / 8)) for k in range(8)]])]),
        ("Table", "s off", [("Wall", fix(box((-1.4, 0.01, -1.2), (-0.2, 0.75, -0.4))))]),
        # A triangular prism: two triangles and three quads.
        ("Wedge", "s 0", [("RedPaint", fix(prism((0.9, -0.9), 0.45, 0.01, 0.6, 3, 0.3)))]),
        # A hexagonal pedestal, smooth shaded in Blender (s 1): n-gon caps.
        ("Pedestal", "s 1", [("BluePaint", fix(prism((0.6, 0.9), 0.35, 0.01, 1.1, 6)))]),
    ]


def fmt(x):
    return "%.6f" % (0.0 if abs(x) < 5e-7 else x)


def main():
    obj = ["# Blender 4.2.1", "# www.blender.org", "mtllib blender.mtl"]
    nv = nvt = nvn = 0
    for name, smooth, parts in objects():
        verts, uvs, norms, faces = [], [], [], []
        for mat, polys in parts:
            for poly in polys:
                n = normal(poly)
                norms.append(n)
                ids = []
                for k, p in enumerate(poly):
                    verts.append(p)
                    a = 2 * math.pi * k / len(poly)
                    uvs.append((0.5 + 0.5 * math.cos(a), 0.5 + 0.5 * math.sin(a)))
                    ids.append("%d/%d/%d" % (nv + len(verts), nvt + len(uvs), nvn + len(norms)))
                faces.append((mat, "f " + " ".join(ids)))
        obj.append("o " + name)
        obj += ["v %s %s %s" % tuple(fmt(x) for x in v) for v in verts]
        obj += ["vn %.4f %.4f %.4f" % tuple(0.0 if abs(x) < 5e-5 else x for x in n) for n in norms]
        obj += ["vt %s %s" % tuple(fmt(x) for x in t) for t in uvs]
        obj.append(smooth)
        current = None
        for mat, f in faces:
            if mat != current:
                obj.append("usemtl " + mat)
                current = mat
            obj.append(f)
        nv, nvt, nvn = nv + len(verts), nvt + len(uvs), nvn + len(norms)
    with open(os.path.join(HERE, "blender.obj"), "w") as f:
        f.write("\n".join(obj) + "\n")

    mtl = ["# Blender 4.2.1 MTL File: 'blender.blend'", "# www.blender.org"]
    for name, kd, ke in MATERIALS:
        mtl += ["", "newmtl " + name, "Ns 250.000000", "Ka 1.000000 1.000000 1.000000",
                "Kd %s %s %s" % tuple(fmt(x) for x in kd), "Ks 0.500000 0.500000 0.500000",
                "Ke %s %s %s" % tuple(fmt(x) for x in ke), "Ni 1.450000", "d 1.000000", "illum 2"]
    with open(os.path.join(HERE, "blender.mtl"), "w") as f:
        f.write("\n".join(mtl) + "\n")


if __name__ == "__main__":
    main()
