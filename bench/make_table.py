#!/usr/bin/env python3
"""A cube resting on a large table top under a ceiling light in a room:
the contact-shadow scene of shooter division (bench/shooters.sh). The
table top is 1.2 x 0.9 m (1.08 m^2) at 0.75 m, on four legs; the cube is
0.25 m, off the top's centre; the light is 0.8 x 0.8 m in a 4 x 4 x 2.5 m
room. Usage: make_table.py OUT.obj (OUT.mtl is written beside it)."""
import os
import sys


def box(lo, hi):
    """The six faces of an axis-aligned box, counter-clockwise from outside."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [
        [(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)],  # top
        [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],  # bottom
        [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],  # +z
        [(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)],  # -z
        [(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)],  # +x
        [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)],  # -x
    ]


def main():
    out = sys.argv[1]
    mtl = os.path.splitext(out)[0] + ".mtl"
    W, H = 2.0, 2.5
    room = [
        [(-W, 0, -W), (-W, 0, W), (W, 0, W), (W, 0, -W)],      # floor, up
        [(-W, H, -W), (W, H, -W), (W, H, W), (-W, H, W)],      # ceiling, down
        [(-W, 0, -W), (W, 0, -W), (W, H, -W), (-W, H, -W)],    # back wall
        [(W, 0, W), (-W, 0, W), (-W, H, W), (W, H, W)],        # front wall
        [(-W, 0, W), (-W, 0, -W), (-W, H, -W), (-W, H, W)],    # left wall
        [(W, 0, -W), (W, 0, W), (W, H, W), (W, H, -W)],        # right wall
    ]
    L, y = 0.4, H - 0.001
    light = [[(-L, y, -L), (L, y, -L), (L, y, L), (-L, y, L)]]
    top = box((-0.6, 0.71, -0.45), (0.6, 0.75, 0.45))
    legs = []
    for x in (-0.55, 0.5):
        for z in (-0.4, 0.35):
            legs += box((x, 0.0, z), (x + 0.05, 0.71, z + 0.05))[2:]  # sides only
    cube = box((0.05, 0.75, -0.1), (0.3, 1.0, 0.15))
    cube = cube[:1] + cube[2:]  # its bottom lies on the top: never lit
    objects = [("Room", "wall", room), ("Light", "light", light),
               ("TableTop", "table", top), ("Legs", "table", legs), ("Cube", "cube", cube)]
    with open(mtl, "w") as f:
        f.write("newmtl wall\nKd 0.75 0.75 0.75\n\n"
                "newmtl light\nKd 0.8 0.8 0.8\nKe 12 12 12\n\n"
                "newmtl table\nKd 0.7 0.45 0.3\n\n"
                "newmtl cube\nKd 0.8 0.8 0.8\n")
    with open(out, "w") as f:
        f.write("# cube on a table top under a ceiling light (bench/make_table.py)\n")
        f.write("mtllib %s\n" % os.path.basename(mtl))
        n = 0
        for name, mat, faces in objects:
            f.write("o %s\nusemtl %s\n" % (name, mat))
            for face in faces:
                for v in face:
                    f.write("v %.6f %.6f %.6f\n" % v)
                f.write("f %s\n" % " ".join(str(n + 1 + i) for i in range(len(face))))
                n += len(face)


main()
