#!/usr/bin/env python3
"""Writes the shipped scenes (cornell, room, maze: .obj + .mtl) and checks them.

    python3 scenes/make_scenes.py [--check-only] [OUTDIR]

OUTDIR defaults to the directory of this script. Standard library only.

Conventions (see the design's "Scene input: OBJ + MTL"): faces are one-sided
and their front is counter-clockwise seen from the lit side, i.e. the Newell
normal points into the air. Every face is built by naming the direction its
front must face; the checks below then verify that independently of how the
face was built:

  * planarity, convexity, no degenerate faces;
  * orientation: at probe points spread over every face, just behind it is
    never air (but solid material, or outside the enclosure), and just in
    front of it is air at some of them (part of a face may be hidden, like
    the floor under a block). "Air" is defined per scene from its solids
    (boxes, prisms) and its enclosure, not from the faces;
  * closure: random rays from points in the air must first hit a face from
    its front; in a closed scene (room, maze) they must hit something, in the
    Cornell box they may leave only through the open front;
  * no two faces coincide (coplanar with overlapping area), either way round;
  * T-junctions (two faces with edges on one line, an end of one inside
    the other: a rasteriser may leave cracks there) are counted. They are
    only where nothing lies behind a crack: ceiling cut round the light
    against the walls, maze walls and strips ending on floor and ceiling
    edges, and joints inside a piece of furniture.

It prints a line per scene, with the default mesh's size (patches of at
most the bounding-box diagonal / 16, each cut into 2 x 2 elements).

The scenes are written only if every check passes.
"""

import math
import os
import random
import sys

# ---------------------------------------------------------------- vectors

def add(a, b): return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def mul(a, s): return (a[0] * s, a[1] * s, a[2] * s)
def dot(a, b): return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0])
def length(a): return math.sqrt(dot(a, a))
def unit(a):
    l = length(a)
    return (a[0] / l, a[1] / l, a[2] / l)


def newell(poly):
    """Newell normal (not normalised; its length is twice the area)."""
    n = [0.0, 0.0, 0.0]
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        n[0] += (p[1] - q[1]) * (p[2] + q[2])
        n[1] += (p[2] - q[2]) * (p[0] + q[0])
        n[2] += (p[0] - q[0]) * (p[1] + q[1])
    return tuple(n)


def centroid(poly):
    return mul(tuple(map(sum, zip(*poly))), 1.0 / len(poly))


def rnd(x):
    """Coordinates are written with 6 decimals at most; -0 becomes 0."""
    x = round(x, 6)
    return 0.0 if x == 0 else x


def fmt(x):
    s = ('%.6f' % x).rstrip('0').rstrip('.')
    return '0' if s in ('-0', '') else s

# ---------------------------------------------------------------- solids
# Solids say where material is; the orientation check asks them, never the
# faces.

class OBox:
    """A box rotated about the vertical axis: local [lo, hi] in a frame with
    origin O and angle A (degrees, counter-clockwise seen from above, i.e.
    local +x turns toward world -z)."""

    def __init__(self, lo, hi, origin=(0.0, 0.0, 0.0), angle=0.0):
        self.lo, self.hi, self.origin = lo, hi, origin
        a = math.radians(angle)
        self.ex = (math.cos(a), 0.0, -math.sin(a))
        self.ey = (0.0, 1.0, 0.0)
        self.ez = (math.sin(a), 0.0, math.cos(a))

    def world(self, p):
        return add(self.origin, add(mul(self.ex, p[0]),
                                    add(mul(self.ey, p[1]), mul(self.ez, p[2]))))

    def local(self, p):
        d = sub(p, self.origin)
        return (dot(d, self.ex), dot(d, self.ey), dot(d, self.ez))

    def contains(self, p):
        q = self.local(p)
        return all(self.lo[i] < q[i] < self.hi[i] for i in range(3))


class Prism:
    """A vertical prism: a polygon footprint in (x, z), from y0 to y1."""

    def __init__(self, foot, y0, y1):
        self.foot, self.y0, self.y1 = foot, y0, y1

    def contains(self, p):
        if not self.y0 < p[1] < self.y1:
            return False
        x, z = p[0], p[2]
        inside = False  # even-odd rule: independent of the footprint's order
        n = len(self.foot)
        for i in range(n):
            (x0, z0), (x1, z1) = self.foot[i], self.foot[(i + 1) % n]
            if (z0 > z) != (z1 > z):
                if x < x0 + (z - z0) * (x1 - x0) / (z1 - z0):
                    inside = not inside
        return inside

# ---------------------------------------------------------------- scenes

class Scene:
    def __init__(self, name, header):
        self.name, self.header = name, header
        self.materials = {}    # name -> (kd, ke, comment), in order of definition
        self.objects = []      # (name, [(material, [points])])
        self.solids = []       # where material is (for the orientation check)
        self.camera = None
        self.inside = None     # point -> bool: inside the enclosure
        self.escape_ok = None  # (origin, direction) -> bool for a ray that hit nothing
        self.air_points = []   # seeds for the ray test

    def material(self, name, kd, ke=(0, 0, 0), comment=None):
        self.materials[name] = (kd, ke, comment)

    def obj(self, name):
        assert name not in [o[0] for o in self.objects], name
        self.objects.append((name, []))

    def face(self, mtl, pts, front):
        """Adds a face whose front faces direction FRONT: the points are
        reversed if their Newell normal disagrees."""
        assert mtl in self.materials, mtl
        pts = [tuple(rnd(c) for c in p) for p in pts]
        if dot(newell(pts), front) < 0:
            pts.reverse()
        self.objects[-1][1].append((mtl, pts))

    def faces(self):
        for oname, fl in self.objects:
            for mtl, pts in fl:
                yield oname, mtl, pts

    def air(self, p):
        return self.inside(p) and not any(s.contains(p) for s in self.solids)

    # -- building blocks

    def box(self, mtl, lo, hi, omit=(), origin=(0.0, 0.0, 0.0), angle=0.0,
            solid=True):
        """A closed box, fronts outward. OMIT names the faces left out because
        they rest on something ('-y' on the floor, '-z' against a wall...),
        in the box's local frame."""
        b = OBox(lo, hi, origin, angle)
        if solid:
            self.solids.append(b)
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        quads = {
            '-x': [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)],
            '+x': [(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)],
            '-y': [(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)],
            '+y': [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)],
            '-z': [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)],
            '+z': [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)],
        }
        axis = {'x': b.ex, 'y': b.ey, 'z': b.ez}
        for key in ('+y', '-z', '+z', '-x', '+x', '-y'):
            if key in omit:
                continue
            d = axis[key[1]]
            front = d if key[0] == '+' else mul(d, -1)
            self.face(mtl, [b.world(p) for p in quads[key]], front)
        return b

    # -- output

    def write(self, outdir):
        lines = ['# %s' % l if l else '#' for l in self.header.split('\n')]
        lines.append('#')
        lines.append('# Generated by make_scenes.py (python3 scenes/make_scenes.py).')
        lines.append('# Faces are one-sided: counter-clockwise seen from the lit side.')
        if self.camera:
            lines.append('# camera ' + ' '.join(fmt(c) for c in self.camera))
        lines.append('mtllib %s.mtl' % self.name)
        index = {}
        for oname, fl in self.objects:
            lines.append('')
            lines.append('o %s' % oname)
            for _, pts in fl:
                for p in pts:
                    if p not in index:
                        index[p] = len(index) + 1
                        lines.append('v %s %s %s' % tuple(fmt(c) for c in p))
            cur = None
            for mtl, pts in fl:
                if mtl != cur:
                    lines.append('usemtl %s' % mtl)
                    cur = mtl
                lines.append('f ' + ' '.join(str(index[p]) for p in pts))
        with open(os.path.join(outdir, self.name + '.obj'), 'w') as f:
            f.write('\n'.join(lines) + '\n')
        m = ['# Materials of %s.obj (Kd diffuse reflectance, Ke emitted exitance).'
             % self.name, '# Generated by make_scenes.py.']
        for name, (kd, ke, comment) in self.materials.items():
            m.append('')
            if comment:
                m.append('# ' + comment)
            m.append('newmtl %s' % name)
            m.append('Kd %s' % ' '.join(fmt(c) for c in kd))
            if any(ke):
                m.append('Ke %s' % ' '.join(fmt(c) for c in ke))
        with open(os.path.join(outdir, self.name + '.mtl'), 'w') as f:
            f.write('\n'.join(m) + '\n')

# The Cornell box's and the room's light sits 0.1 mm / 1 mm below the
# ceiling, which has a hole there (cut into 8 faces around it). False keeps
# the ceiling one face, whole behind the light: no seams along the cuts, but
# the hidden ceiling behind the light is dark and shades a dark rim round it.
CEILING_HOLES = True

# ---------------------------------------------------------------- Cornell box

def cornell(holes=False):
    """HOLES: the floor is cut around the blocks' footprints (cornell-holes),
    so that no floor lies in the dark under them."""
    s = Scene('cornell-holes' if holes else 'cornell', """\
Cornell box, after the Cornell University Program of Computer Graphics
"Cornell Box" data page (https://www.graphics.cornell.edu/online/box/data.html).
Units are millimetres; the box is open at z = 0, toward the camera.

Changes from the published data:
* The published floor edge and red wall run from x = 552.8 (z = 0) to
  549.6 (z = 559.2) at floor level but x = 556 at the ceiling, which leaves
  the red wall 3 mm out of plane; here the box is squared to x = 556.
* The light (published at y = 548.8, coincident with the ceiling) is its
  own face 0.1 mm below the ceiling, facing down, and the ceiling has a
  hole where the light is (cut into 8 pieces around it).
* The blocks' bottom faces, which rest on the floor, are left out.
* Reflectances are RGB approximations of the published spectra; the light's
  Ke is in arbitrary units (pictures are auto-exposed).
The camera is the published one: at (278, 273, -800), looking along +z,
focal length 35 mm on a 25 mm film: vertical field of view 39.3 degrees.""")
    if holes:
        s.header += """
Here the floor is cut into convex pieces around the blocks' footprints:
no floor lies in the dark under the blocks."""
    s.material('white', (0.73, 0.73, 0.73))
    s.material('red', (0.63, 0.065, 0.05))
    s.material('green', (0.14, 0.45, 0.091))
    s.material('light', (0.78, 0.78, 0.78), (17, 12, 4))
    s.camera = (278, 273, -800, 278, 273, 0, 39.3)

    X, Y, Z = 556.0, 548.8, 559.2
    up, down = (0, 1, 0), (0, -1, 0)
    short_top = [(130, 65), (82, 225), (240, 272), (290, 114)]
    tall_top = [(423, 247), (265, 296), (314, 456), (472, 406)]
    s.obj('floor')
    if holes:
        for piece in floor_around([short_top, tall_top], X, Z):
            s.face('white', [(x, 0, z) for x, z in piece], up)
    else:
        s.face('white', [(X, 0, 0), (0, 0, 0), (0, 0, Z), (X, 0, Z)], up)
    s.obj('ceiling')
    if CEILING_HOLES:
        xs, zs = [0.0, 213.0, 343.0, X], [0.0, 227.0, 332.0, Z]
        for i in range(3):
            for j in range(3):
                if (i, j) == (1, 1):
                    continue  # the light's hole
                s.face('white', [(xs[i], Y, zs[j]), (xs[i + 1], Y, zs[j]),
                                 (xs[i + 1], Y, zs[j + 1]), (xs[i], Y, zs[j + 1])], down)
    else:
        s.face('white', [(0, Y, 0), (X, Y, 0), (X, Y, Z), (0, Y, Z)], down)
    s.obj('light')
    LY = 548.7
    s.face('light', [(343.0, LY, 227.0), (343.0, LY, 332.0),
                     (213.0, LY, 332.0), (213.0, LY, 227.0)], down)
    s.solids.append(Prism([(213, 227), (343, 227), (343, 332), (213, 332)], LY, Y + 1))
    s.obj('back_wall')
    s.face('white', [(X, 0, Z), (0, 0, Z), (0, Y, Z), (X, Y, Z)], (0, 0, -1))
    s.obj('red_wall')
    s.face('red', [(X, 0, 0), (X, 0, Z), (X, Y, Z), (X, Y, 0)], (-1, 0, 0))
    s.obj('green_wall')
    s.face('green', [(0, 0, Z), (0, 0, 0), (0, Y, 0), (0, Y, Z)], (1, 0, 0))

    def block(name, top, h):
        """TOP: the published top face's (x, z) corners; sides down to y=0."""
        s.obj(name)
        c = centroid([(x, 0, z) for x, z in top])
        s.face('white', [(x, h, z) for x, z in top], up)
        for k in range(4):
            (xa, za), (xb, zb) = top[k], top[(k + 1) % 4]
            quad = [(xa, 0, za), (xa, h, za), (xb, h, zb), (xb, 0, zb)]
            out = sub(centroid(quad), (c[0], h / 2, c[2]))
            s.face('white', quad, (out[0], 0, out[2]))
        s.solids.append(Prism(top, 0, h))

    block('short_block', short_top, 165.0)
    block('tall_block', tall_top, 330.0)

    s.inside = lambda p: 0 < p[0] < X and 0 < p[1] < Y and 0 < p[2] < Z

    def escape_ok(o, d):
        # A ray that hits nothing must leave through the open front (z = 0).
        if d[2] >= 0:
            return False
        t = -o[2] / d[2]
        p = add(o, mul(d, t))
        return 0 <= p[0] <= X and 0 <= p[1] <= Y
    s.escape_ok = escape_ok
    rng = random.Random(1)
    while len(s.air_points) < 12:
        p = (rng.uniform(1, X - 1), rng.uniform(1, Y - 1), rng.uniform(1, Z - 1))
        if s.air(p):
            s.air_points.append(p)
    return s


def floor_around(holes, X, Z):
    """The rectangle [0, X] x [0, Z] less the convex HOLES ((x, z) corners),
    as convex pieces: cut at every hole corner's x, each slab's free z
    intervals between the holes' edges are trapezoids (triangles where an
    interval ends in a corner). Pieces meet hole corners in T-junctions."""
    xs = sorted(set([0.0, X] + [float(x) for h in holes for x, _ in h]))
    def cut(h, x):  # the z interval of convex polygon h on the line at x, or None
        zs = []
        for i in range(len(h)):
            (xa, za), (xb, zb) = h[i], h[(i + 1) % len(h)]
            if min(xa, xb) <= x <= max(xa, xb):
                zs += [za, zb] if xa == xb else [za + (x - xa) * (zb - za) / (xb - xa)]
        return (min(zs), max(zs)) if zs else None
    pieces = []
    for x0, x1 in zip(xs, xs[1:]):
        xm = 0.5 * (x0 + x1)
        inside = sorted([h for h in holes if cut(h, xm)], key=lambda h: cut(h, xm)[0])
        lo0 = lo1 = 0.0
        for h in inside + [None]:
            hi0, hi1 = (cut(h, x0)[0], cut(h, x1)[0]) if h else (Z, Z)
            pts = [(x0, lo0), (x1, lo1), (x1, hi1), (x0, hi0)]
            pieces.append([p for i, p in enumerate(pts) if p != pts[i - 1]])
            if h:
                lo0, lo1 = cut(h, x0)[1], cut(h, x1)[1]
    return pieces

# ---------------------------------------------------------------- room

def room():
    W, H, D = 6.0, 3.0, 5.0  # x, y, z
    s = Scene('room', """\
"Room": a closed room (%g x %g x %g units, y up) with furniture and one
light, after the "Room" test scene of Sindlar & Pelikan, "Parallel Radiosity
on a Cluster of Workstations" (the original geometry is not published; this
one is made up). A table with four legs and two chairs under a rectangular
ceiling light, a bookshelf with books, a sofa with cushions and a rug, a
sideboard with a vase and a picture on the back wall. Coloured walls and
furniture show colour bleeding. Box faces that rest on the floor, on other
furniture or against a wall are left out.""" % (W, H, D))
    m = s.material
    m('floor', (0.55, 0.38, 0.22), comment='warm wooden floor')
    m('ceiling', (0.80, 0.80, 0.80))
    m('wall_white', (0.75, 0.75, 0.72))
    m('wall_orange', (0.80, 0.50, 0.28))
    m('wall_blue', (0.45, 0.58, 0.78))
    m('wall_cream', (0.78, 0.74, 0.62))
    m('light', (0.80, 0.80, 0.80), (30, 28, 24), 'the only light source')
    m('wood_light', (0.60, 0.45, 0.28))
    m('wood_dark', (0.40, 0.24, 0.13))
    m('chair_red', (0.70, 0.14, 0.10))
    m('sofa_blue', (0.15, 0.28, 0.62))
    m('cushion_yellow', (0.85, 0.70, 0.18))
    m('rug_red', (0.62, 0.12, 0.10))
    m('book_green', (0.15, 0.50, 0.20))
    m('book_red', (0.65, 0.12, 0.12))
    m('book_blue', (0.15, 0.25, 0.60))
    m('book_white', (0.80, 0.78, 0.70))
    m('vase_white', (0.85, 0.85, 0.85))
    m('picture_sky', (0.25, 0.50, 0.80), comment='the painting: blue sky over a green field')
    m('picture_field', (0.25, 0.55, 0.15))
    s.camera = (5.8, 1.75, 4.85, 2.0, 0.95, 1.2, 65)

    # --- the shell: floor, four walls, ceiling with a hole for the light
    s.obj('floor')
    s.face('floor', [(0, 0, 0), (W, 0, 0), (W, 0, D), (0, 0, D)], (0, 1, 0))
    s.obj('walls')
    s.face('wall_cream', [(0, 0, 0), (W, 0, 0), (W, H, 0), (0, H, 0)], (0, 0, 1))   # back, z=0
    s.face('wall_white', [(0, 0, D), (W, 0, D), (W, H, D), (0, H, D)], (0, 0, -1))  # front, z=D
    s.face('wall_orange', [(0, 0, 0), (0, 0, D), (0, H, D), (0, H, 0)], (1, 0, 0))  # left, x=0
    s.face('wall_blue', [(W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0)], (-1, 0, 0))   # right, x=W
    lx0, lx1, lz0, lz1 = 2.4, 3.6, 2.0, 2.8   # the light panel, 1.2 x 0.8
    s.obj('ceiling')
    if CEILING_HOLES:
        xs, zs = [0, lx0, lx1, W], [0, lz0, lz1, D]
        for i in range(3):
            for j in range(3):
                if (i, j) != (1, 1):
                    s.face('ceiling', [(xs[i], H, zs[j]), (xs[i + 1], H, zs[j]),
                                       (xs[i + 1], H, zs[j + 1]), (xs[i], H, zs[j + 1])],
                           (0, -1, 0))
    else:
        s.face('ceiling', [(0, H, 0), (W, H, 0), (W, H, D), (0, H, D)], (0, -1, 0))
    s.obj('light')
    ly = H - 0.001
    s.face('light', [(lx0, ly, lz0), (lx1, ly, lz0), (lx1, ly, lz1), (lx0, ly, lz1)],
           (0, -1, 0))
    s.solids.append(OBox((lx0, ly, lz0), (lx1, H + 1, lz1)))

    # --- table under the light
    tx0, tx1, tz0, tz1 = 2.2, 3.8, 1.95, 2.85
    th, tt, leg, inset = 0.72, 0.06, 0.07, 0.06
    s.obj('table')
    s.box('wood_light', (tx0, th, tz0), (tx1, th + tt, tz1))
    for i, x in enumerate((tx0 + inset, tx1 - inset - leg)):
        for j, z in enumerate((tz0 + inset, tz1 - inset - leg)):
            s.obj('table_leg_%d' % (2 * i + j + 1))
            s.box('wood_light', (x, 0, z), (x + leg, th, z + leg), omit=('-y', '+y'))

    # --- two chairs: local frame, seat [0,0.45]^2, the back at local z = 0
    def chair(name, origin, angle):
        sw, sh, st, cl, bh, bt = 0.45, 0.45, 0.05, 0.04, 0.5, 0.04
        s.obj(name + '_seat')
        s.box('chair_red', (0, sh, 0), (sw, sh + st, sw), origin=origin, angle=angle)
        for i, x in enumerate((0.02, sw - 0.02 - cl)):
            for j, z in enumerate((0.02, sw - 0.02 - cl)):
                s.obj('%s_leg_%d' % (name, 2 * i + j + 1))
                s.box('chair_red', (x, 0, z), (x + cl, sh, z + cl), omit=('-y', '+y'),
                      origin=origin, angle=angle)
        s.obj(name + '_back')
        s.box('chair_red', (0, sh + st, 0), (sw, sh + st + bh, bt), omit=('-y',),
              origin=origin, angle=angle)
    # Chair 1 behind the table (its back toward the back wall), turned a
    # little; chair 2 in front of it, back toward the camera side.
    chair('chair_1', (2.45, 0, 1.38), -12.0)
    chair('chair_2', (3.75, 0, 3.38), 180.0)

    # --- bookshelf against the back wall (z = 0), x in [0.6, 1.8]
    bx0, bx1, bd, bh, pt = 0.6, 1.8, 0.35, 2.0, 0.05
    s.obj('bookshelf')
    s.box('wood_dark', (bx0, 0, 0), (bx0 + pt, bh, bd), omit=('-y', '+y', '-z'))
    s.box('wood_dark', (bx1 - pt, 0, 0), (bx1, bh, bd), omit=('-y', '+y', '-z'))
    s.box('wood_dark', (bx0, bh, 0), (bx1, bh + pt, bd), omit=('-z',))        # top board
    s.box('wood_dark', (bx0 + pt, 0, 0), (bx1 - pt, 0.08, bd),
          omit=('-y', '-z', '-x', '+x'))                                      # plinth
    shelves = [0.08, 0.55, 1.02, 1.49]  # top surfaces books stand on
    for y in shelves[1:]:
        s.box('wood_dark', (bx0 + pt, y - 0.04, 0), (bx1 - pt, y, bd),
              omit=('-z', '-x', '+x'))
    books = [  # (shelf, x0, x1, height, material)
        (0, 0.66, 0.98, 0.30, 'book_red'), (0, 1.02, 1.20, 0.26, 'book_white'),
        (0, 1.40, 1.74, 0.34, 'book_blue'),
        (1, 0.66, 1.05, 0.28, 'book_green'), (1, 1.30, 1.56, 0.24, 'book_red'),
        (2, 0.80, 1.22, 0.30, 'book_blue'), (2, 1.26, 1.46, 0.22, 'book_white'),
        (3, 0.66, 0.92, 0.26, 'book_white'), (3, 1.20, 1.74, 0.32, 'book_green'),
    ]
    for k, (sh, x0, x1, h, mtl) in enumerate(books):
        s.obj('books_%d' % (k + 1))
        y = shelves[sh]
        s.box(mtl, (x0, y, 0.04), (x1, y + h, 0.29), omit=('-y',))

    # --- sideboard with a vase, and a picture above it (back wall)
    s.obj('sideboard')
    s.box('wood_dark', (3.0, 0, 0), (4.6, 0.8, 0.45), omit=('-y', '-z'))
    s.obj('vase')
    s.box('vase_white', (4.1, 0.8, 0.15), (4.26, 1.12, 0.31), omit=('-y',))
    # a framed painting: four bars around a canvas 2 cm deep, sky over a field
    px0, px1, py0, py1, fw, fd, cd = 3.1, 4.5, 1.3, 2.2, 0.06, 0.04, 0.02
    s.obj('picture_frame')
    s.box('wood_dark', (px0, py1 - fw, 0), (px1, py1, fd), omit=('-z',))
    s.box('wood_dark', (px0, py0, 0), (px1, py0 + fw, fd), omit=('-z',))
    s.box('wood_dark', (px0, py0 + fw, 0), (px0 + fw, py1 - fw, fd), omit=('-z', '-y', '+y'))
    s.box('wood_dark', (px1 - fw, py0 + fw, 0), (px1, py1 - fw, fd), omit=('-z', '-y', '+y'))
    s.obj('picture')
    cx0, cx1, cy0, cy1 = px0 + fw, px1 - fw, py0 + fw, py1 - fw
    cy = cy0 + 0.4 * (cy1 - cy0)
    s.face('picture_field', [(cx0, cy0, cd), (cx1, cy0, cd), (cx1, cy, cd), (cx0, cy, cd)],
           (0, 0, 1))
    s.face('picture_sky', [(cx0, cy, cd), (cx1, cy, cd), (cx1, cy1, cd), (cx0, cy1, cd)],
           (0, 0, 1))
    s.solids.append(OBox((cx0, cy0, -1), (cx1, cy1, cd)))

    # --- sofa against the left wall (x = 0)
    sz0, sz1 = 1.3, 3.5
    s.obj('sofa')
    s.box('sofa_blue', (0, 0, sz0), (0.2, 0.85, sz1), omit=('-y', '-x'))           # backrest
    s.box('sofa_blue', (0.2, 0, sz0), (0.9, 0.6, sz0 + 0.2), omit=('-y', '-x'))    # arms
    s.box('sofa_blue', (0.2, 0, sz1 - 0.2), (0.9, 0.6, sz1), omit=('-y', '-x'))
    s.box('sofa_blue', (0.2, 0, sz0 + 0.2), (0.9, 0.42, sz1 - 0.2),
          omit=('-y', '-x', '-z', '+z'))                                          # seat
    s.obj('cushions')
    zm = (sz0 + sz1) / 2
    for z0, z1 in ((sz0 + 0.25, zm - 0.02), (zm + 0.02, sz1 - 0.25)):
        s.box('cushion_yellow', (0.34, 0.42, z0), (0.86, 0.52, z1), omit=('-y',))
        s.box('cushion_yellow', (0.2, 0.42, z0), (0.32, 0.78, z1), omit=('-y', '-x'))

    # --- rug in front of the sofa: one face just above the floor
    s.obj('rug')
    ry = 0.004
    s.face('rug_red', [(1.05, ry, 1.55), (2.05, ry, 1.55), (2.05, ry, 3.25),
                       (1.05, ry, 3.25)], (0, 1, 0))
    s.solids.append(OBox((1.05, -1, 1.55), (2.05, ry, 3.25)))

    s.inside = lambda p: 0 < p[0] < W and 0 < p[1] < H and 0 < p[2] < D
    s.escape_ok = lambda o, d: False
    rng = random.Random(2)
    while len(s.air_points) < 16:
        p = (rng.uniform(0.02, W - 0.02), rng.uniform(0.02, H - 0.02),
             rng.uniform(0.02, D - 0.02))
        if s.air(p):
            s.air_points.append(p)
    s.air_points += [(3.0, 0.3, 2.4), (0.5, 0.3, 0.1), (1.55, 1.2, 0.2)]  # under the table, in the shelf
    return s

# ---------------------------------------------------------------- maze

MAZE = [
    # A perfect 4 x 4 maze: the pairs of neighbouring cells (i, j) (i along
    # x, j along z) that a passage joins. The map in maze.obj's header is
    # drawn from this list.
    ((0, 0), (1, 0)), ((1, 0), (2, 0)), ((2, 0), (3, 0)),
    ((3, 0), (3, 1)), ((3, 1), (3, 2)), ((3, 2), (3, 3)),
    ((3, 3), (2, 3)), ((2, 3), (1, 3)), ((1, 3), (0, 3)),
    ((0, 3), (0, 2)), ((0, 2), (0, 1)),
    ((1, 0), (1, 1)), ((1, 1), (1, 2)), ((1, 2), (2, 2)), ((2, 2), (2, 1)),
]


def maze():
    C, H = 1.5, 2.5  # block size (corridor width, wall thickness), height
    n = 4
    s = Scene('maze', """\
"Maze": corridors with four light sources, after the "Maze" test scene of
Sindlar & Pelikan, "Parallel Radiosity on a Cluster of Workstations" (the
original geometry is not published; this one is made up). A perfect 4 x 4
maze on a grid of %g-unit blocks: corridors %g wide and %g high between
walls %g thick, 12 x 12 units outside the outer walls (10.5 x 10.5 inside).
Four small ceiling panels in different corridors (warm white, blue, red,
green) light it, so most pairs of surfaces cannot see each other. Only the
faces toward the corridors exist: each straight corridor's floor and
ceiling is one face, each straight run of wall is one face, and walls meet
each other on shared edges (T-junctions only where a wall or strip ends on
a floor or ceiling edge, with nothing behind).""" % (C, C, H, C))
    s.material('floor', (0.50, 0.46, 0.40), comment='stone floor')
    s.material('ceiling', (0.72, 0.72, 0.72))
    s.material('wall', (0.74, 0.72, 0.68))
    s.material('light_white', (0.8, 0.8, 0.8), (22, 20, 16))
    s.material('light_blue', (0.8, 0.8, 0.8), (7, 11, 26))
    s.material('light_red', (0.8, 0.8, 0.8), (26, 8, 5))
    s.material('light_green', (0.8, 0.8, 0.8), (8, 24, 8))

    g = 2 * n + 1  # blocks per side, the outer ring solid
    open_ = set()
    for i in range(n):
        for j in range(n):
            open_.add((2 * i + 1, 2 * j + 1))
    for (a, b) in MAZE:
        assert abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1, (a, b)
        open_.add((a[0] + b[0] + 1, a[1] + b[1] + 1))
    assert len(open_) == n * n + n * n - 1, 'the maze is not a tree'

    def lo(b):  # world coordinate of a block's low edge; block 1 starts at 0
        return (b - 1) * C

    lights = [((1, 0), 'light_white', 'W'), ((2, 2), 'light_blue', 'B'),
              ((3, 1), 'light_red', 'R'), ((0, 2), 'light_green', 'G')]
    # The map, for the header: '#' solid, letters the lights, C the camera.
    mark = {(2 * ci + 1, 2 * cj + 1): ch for (ci, cj), _, ch in lights}
    mark[(1, 1)] = 'C'
    rows = [''.join(2 * mark.get((bi, bj), ' ' if (bi, bj) in open_ else '#')
                    for bi in range(g)) for bj in range(g)]
    s.header += ('\n\nMap, from above (x to the right, z down, a character pair per\n'
                 'block; W, B, R, G: white, blue, red and green lights, C: camera):\n\n' +
                 '\n'.join('    ' + r for r in rows))

    # Floor and ceiling: the open blocks cut into straight strips, longest
    # first, so that each corridor is one face. (The program shades each
    # face on its own, so every face boundary can show as a seam.)
    strips = []
    left = set(open_)
    while left:
        best = None
        for bi, bj in sorted(left):
            for di, dj in ((1, 0), (0, 1)):
                k = 1
                while (bi + k * di, bj + k * dj) in left:
                    k += 1
                if best is None or k > best[0]:
                    best = (k, bi, bj, di, dj)
        k, bi, bj, di, dj = best
        for t in range(k):
            left.discard((bi + t * di, bj + t * dj))
        strips.append((lo(bi), lo(bj), lo(bi + (k - 1) * di) + C, lo(bj + (k - 1) * dj) + C))
    strips.sort(key=lambda r: (r[1], r[0]))
    s.obj('floor')
    for x0, z0, x1, z1 in strips:
        s.face('floor', [(x0, 0, z0), (x1, 0, z0), (x1, 0, z1), (x0, 0, z1)], (0, 1, 0))
    s.obj('ceiling')
    for x0, z0, x1, z1 in strips:
        s.face('ceiling', [(x0, H, z0), (x1, H, z0), (x1, H, z1), (x0, H, z1)], (0, -1, 0))

    # Walls: every side of an open block toward a solid one, merged along
    # straight runs. Runs end where a corridor opens or turns, which is where
    # the neighbouring run starts: walls meet on shared edges.
    sides = {}  # (axis, side, line) -> block positions along the line
    for bi, bj in open_:
        if (bi - 1, bj) not in open_:
            sides.setdefault(('x', -1, bi), []).append(bj)
        if (bi + 1, bj) not in open_:
            sides.setdefault(('x', +1, bi), []).append(bj)
        if (bi, bj - 1) not in open_:
            sides.setdefault(('z', -1, bj), []).append(bi)
        if (bi, bj + 1) not in open_:
            sides.setdefault(('z', +1, bj), []).append(bi)
    s.obj('walls')
    for (axis, side, line), ks in sorted(sides.items()):
        ks.sort()
        runs = []
        for k in ks:
            if runs and runs[-1][1] == k - 1:
                runs[-1][1] = k
            else:
                runs.append([k, k])
        w = lo(line) + (C if side > 0 else 0)  # the wall's plane
        for a, b in runs:
            u0, u1 = lo(a), lo(b) + C
            if axis == 'x':
                s.face('wall', [(w, 0, u0), (w, 0, u1), (w, H, u1), (w, H, u0)],
                       (-side, 0, 0))
            else:
                s.face('wall', [(u0, 0, w), (u1, 0, w), (u1, H, w), (u0, H, w)],
                       (0, 0, -side))

    # Lights: 0.5 x 0.5 panels 1 cm below the middle of a cell's ceiling,
    # facing down; the ceiling stays whole behind them.
    for k, ((ci, cj), mtl, _) in enumerate(lights):
        s.obj('light_%d' % (k + 1))
        x0, z0 = lo(2 * ci + 1) + C / 3, lo(2 * cj + 1) + C / 3
        x1, z1, y = x0 + C / 3, z0 + C / 3, H - 0.01
        s.face(mtl, [(x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1)], (0, -1, 0))
        s.solids.append(OBox((x0, y, z0), (x1, H + 1, z1)))

    def inside(p):
        if not 0 < p[1] < H:
            return False
        bi, bj = int(math.floor(p[0] / C)) + 1, int(math.floor(p[2] / C)) + 1
        return (bi, bj) in open_
    s.inside = inside
    s.escape_ok = lambda o, d: False
    for bi, bj in sorted(open_):
        s.air_points.append((lo(bi) + 0.7, 1.3, lo(bj) + 0.8))
    # The camera: in cell (0,0) against its west wall, looking down the
    # corridor along +x toward the white light and the turn at the end.
    s.camera = (0.2, 1.55, 0.75, 10.5, 1.15, 0.75, 55)
    return s

# ---------------------------------------------------------------- checks

def ray_hit(o, d, polys):
    """Nearest hit: (t, index, front?) or None. POLYS: (pts, n, off, bbox)."""
    best = None
    for k, (pts, n, off, _) in enumerate(polys):
        dn = dot(d, n)
        if abs(dn) < 1e-12:
            continue
        t = (off - dot(o, n)) / dn
        if t <= 1e-9 or (best and t >= best[0]):
            continue
        p = add(o, mul(d, t))
        # inside the convex polygon: on the inner side of every edge
        ok = True
        m = len(pts)
        for i in range(m):
            a, b = pts[i], pts[(i + 1) % m]
            if dot(cross(sub(b, a), sub(p, a)), n) < -1e-12:
                ok = False
                break
        if ok:
            best = (t, k, dn < 0)
    return best


def clip_convex(subject, clipper):
    """Sutherland-Hodgman in 2D; CLIPPER counter-clockwise."""
    out = subject
    m = len(clipper)
    for i in range(m):
        a, b = clipper[i], clipper[(i + 1) % m]
        inp, out = out, []
        if not inp:
            break
        def side(p):
            return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
        for j in range(len(inp)):
            p, q = inp[j], inp[(j + 1) % len(inp)]
            sp, sq = side(p), side(q)
            if sp >= 0:
                out.append(p)
            if (sp >= 0) != (sq >= 0):
                t = sp / (sp - sq)
                out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def area2(poly):
    return 0.5 * sum(poly[i][0] * poly[(i + 1) % len(poly)][1] -
                     poly[(i + 1) % len(poly)][0] * poly[i][1]
                     for i in range(len(poly)))


def check(s, rays=300):
    """Returns a list of problems (empty: all good) and prints a summary."""
    errors = []
    faces = list(s.faces())
    lo = [min(p[i] for _, _, pts in faces for p in pts) for i in range(3)]
    hi = [max(p[i] for _, _, pts in faces for p in pts) for i in range(3)]
    diag = length(sub(hi, lo))
    eps = 1e-4 * diag
    polys = []
    for k, (oname, mtl, pts) in enumerate(faces):
        where = '%s: face %d (%s)' % (s.name, k, oname)
        nn = newell(pts)
        area = 0.5 * length(nn)
        if area < 1e-9 * diag * diag:
            errors.append(where + ': degenerate')
            continue
        n = unit(nn)
        c = centroid(pts)
        off = dot(n, c)
        size = max(length(sub(p, q)) for p in pts for q in pts)
        dev = max(abs(dot(n, p) - off) for p in pts)
        if dev > 1e-6 * size + 1e-6:
            errors.append(where + ': not planar (%g)' % dev)
        for i in range(len(pts)):
            a, b, cc = pts[i - 1], pts[i], pts[(i + 1) % len(pts)]
            if dot(cross(sub(b, a), sub(cc, b)), n) <= 0:
                errors.append(where + ': not strictly convex at vertex %d' % i)
        # orientation: never air behind, air in front somewhere (part of a
        # face may be hidden, e.g. the floor under a block)
        probes = [c] + [add(mul(c, w), mul(p, 1 - w)) for w in (0.2, 0.5, 0.9)
                        for p in pts]
        behind = [q for q in probes if s.air(sub(q, mul(n, eps)))]
        if behind:
            errors.append(where + ': air behind it at %s' % (behind[0],))
        if not any(s.air(add(q, mul(n, eps))) for q in probes):
            errors.append(where + ': no air in front of it')
        polys.append((pts, n, off, None))
    if errors:
        return errors

    # coincident faces: coplanar (either orientation) with overlapping area
    for a in range(len(polys)):
        pa, na, oa, _ = polys[a]
        for b in range(a + 1, len(polys)):
            pb, nb, ob, _ = polys[b]
            if abs(abs(dot(na, nb)) - 1) > 1e-9:
                continue
            sgn = 1 if dot(na, nb) > 0 else -1
            if abs(oa - sgn * ob) > 1e-7 * diag:
                continue
            # project on the plane of a, both counter-clockwise
            u = unit(sub(pa[1], pa[0]))
            v = cross(na, u)
            A = [(dot(p, u), dot(p, v)) for p in pa]
            B = [(dot(p, u), dot(p, v)) for p in pb]
            if area2(B) < 0:
                B.reverse()
            inter = clip_convex(A, B)
            if len(inter) >= 3 and area2(inter) > 1e-9 * diag * diag:
                errors.append('%s: faces %d and %d coincide (overlap %g)' %
                              (s.name, a, b, area2(inter)))

    # T-junctions: two faces with edges along the same line, an endpoint of
    # one strictly inside the other (where a rasteriser may leave cracks)
    tjs = set()
    edges = [(pts[i], pts[(i + 1) % len(pts)]) for pts, _, _, _ in polys
             for i in range(len(pts))]
    for a, b in edges:
        ab = sub(b, a)
        l2 = dot(ab, ab)
        def on_line(p):
            t = dot(sub(p, a), ab) / l2
            d = sub(sub(p, a), mul(ab, t))
            return t, dot(d, d) < 1e-14 * l2
        for c, d in edges:
            tc, lc = on_line(c)
            td, ld = on_line(d)
            if not (lc and ld) or max(tc, td) <= 1e-9 or min(tc, td) >= 1 - 1e-9:
                continue  # not collinear, or not overlapping
            for p, t in ((c, tc), (d, td)):
                if 1e-9 < t < 1 - 1e-9:
                    tjs.add((a, b, p))
    tj = len(tjs)
    # closure: random rays from points in the air
    rng = random.Random(7)
    bad = 0
    for o in s.air_points:
        if not s.air(o):
            errors.append('%s: seed %s is not in the air' % (s.name, o))
            continue
        for _ in range(rays):
            while True:
                d = (rng.gauss(0, 1), rng.gauss(0, 1), rng.gauss(0, 1))
                if length(d) > 1e-6:
                    break
            d = unit(d)
            h = ray_hit(o, d, polys)
            if h is None:
                if not s.escape_ok(o, d):
                    bad += 1
                    if bad <= 5:
                        errors.append('%s: ray from %s along %s escapes' % (s.name, o, d))
            elif not h[2]:
                bad += 1
                if bad <= 5:
                    errors.append('%s: ray from %s along %s hits the back of face %d' %
                                  (s.name, o, d, h[1]))
    if bad:
        errors.append('%s: %d bad rays' % (s.name, bad))

    # summary, with the default mesh's size estimated the way the program
    # cuts faces: patches of at most diag/16, each 2 x 2 elements
    ps = diag / 16
    patches = 0
    worst = 1
    for pts, n, _, _ in polys:
        if len(pts) == 4:
            e = [length(sub(pts[(i + 1) % 4], pts[i])) for i in range(4)]
            patches += math.ceil(max(e[0], e[2]) / ps) * math.ceil(max(e[1], e[3]) / ps)
            worst = max(worst, max(e) / min(e))
        else:
            patches += 1
    print('%-8s %3d faces, %2d objects, %3d vertices used, bbox %s .. %s, '
          'diagonal %.4g, ~%d patches ~%d elements, T-junctions %d, '
          'worst aspect %.1f, %d rays from %d points ok' %
          (s.name, len(polys), len(s.objects), len(set(p for pts, _, _, _ in polys for p in pts)),
           tuple(round(x, 3) for x in lo), tuple(round(x, 3) for x in hi),
           diag, patches, 4 * patches, tj, worst,
           rays * len(s.air_points) - bad, len(s.air_points)))
    return errors


def main(argv):
    check_only = '--check-only' in argv
    args = [a for a in argv if not a.startswith('--')]
    outdir = args[0] if args else os.path.dirname(os.path.abspath(__file__))
    ok = True
    for make in (cornell, lambda: cornell(holes=True), room, maze):
        s = make()
        errors = check(s)
        for e in errors:
            print('make_scenes: ' + e, file=sys.stderr)
        if errors:
            ok = False
        elif not check_only:
            s.write(outdir)
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
