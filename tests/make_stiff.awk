# Generates the stiff and extreme scenes of tests/stiff.sh and
# bench/stiff.sh: OBJ on standard output, its MTL into the file `mtl`.
#   awk -v scene=NAME -v mtl=DIR/NAME.mtl [-v scale=S] [-v n=N] \
#       -f tests/make_stiff.awk > DIR/NAME.obj
# Every coordinate is multiplied by `scale` (default 1), so that one scene
# at 1e-4 and 1e4 must give the same radiosities. Scenes (faces listed in
# the order of the comments below; result.csv's `face` is that order):
#   hdr    a unit room, every wall Kd 0.5; the ceiling cut 3 x 3 round a
#          0.01 x 0.01 light of Ke 1e6 (face 4 of the ceiling's 9); the
#          floor cut 3 x 3 round a 0.1 x 0.1 dim light of Ke 1e-6.
#          Faces: 0..8 ceiling (4 = light), 9..17 floor (13 = dim light),
#          18..21 walls y=0, y=1, x=0, x=1.
#   thin   a unit room lit by a 0.2 x 0.2 ceiling light (Ke 10), with
#          awkward geometry: the floor cut into two halves and a sliver
#          1 x 1e-4 (aspect 1e4) between them; a fin seen edge-on by the
#          light (both sides); a plate that pierces the floor (both sides);
#          a plate lying on the floor (coincident); a 1e-3 square floating
#          at z = 0.3; a 0.1 cube in the floor's corner, touching two walls
#          and the floor along edges and at a corner.
#          Faces: 0..8 ceiling (4 = light), 9 floor x<0.5, 10 sliver,
#          11 floor x>0.5001, 12..15 walls, 16,17 fin, 18,19 piercing
#          plate, 20 coincident plate, 21 small square, 22..27 cube.
#   leak   three closed unit rooms: A = [0,1]^3 with a ceiling light,
#          B = [1,2]x[0,1]x[0,1] sharing A's wall x=1 (coincident faces
#          back to back, floors and ceilings touching along an edge) and
#          C = [1,2]x[1,2]x[1,2] touching A at the corner (1,1,1) only.
#          Faces: 0..8 A's ceiling (4 = light), 9 A's floor, 10..13 A's
#          walls; 14..19 room B, 20..25 room C (ceiling, floor, 4 walls).
#   big    a unit room whose floor is an n x n grid of quads (default
#          n = 448: 200,704 floor faces, 4 walls and a ceiling light).
# Other variables: sliver (thin: the sliver's width, default 1e-4), kd and
# kd2 (thin: the walls' and the white plates' Kd, default 0.5 and 0.8).
function P(x, y, z) {
  printf "v %.17g %.17g %.17g\n", x * scale, y * scale, z * scale
  return ++nv
}
# A quad of 4 points given by index, in the order given (counter-clockwise
# seen from the front).
function Q(a, b, c, d, m) {
  if (m != cur) { print "usemtl " m; cur = m }
  print "f " a " " b " " c " " d
  ++nf
}
# An axis-aligned rectangle in plane `axis` = k (0 x, 1 y, 2 z) spanning
# [u0,u1] x [v0,v1] in the other two axes (in x,y,z order), facing +axis
# when dir > 0, else -axis.
function R(axis, k, u0, u1, v0, v1, dir, m,   a, b, c, d) {
  if (axis == 2) { a = P(u0, v0, k); b = P(u1, v0, k); c = P(u1, v1, k); d = P(u0, v1, k) }
  else if (axis == 1) { a = P(u0, k, v0); b = P(u0, k, v1); c = P(u1, k, v1); d = P(u1, k, v0) }
  else { a = P(k, u0, v0); b = P(k, u1, v0); c = P(k, u1, v1); d = P(k, u0, v1) }
  if (dir > 0) Q(a, b, c, d, m); else Q(d, c, b, a, m)
}
# A plane z = k cut 3 x 3 round the square [c0,c1]^2 (shifted by ox, oy),
# the middle one of material mid, the rest m; facing dir.
function Grid(k, c0, c1, ox, oy, dir, m, mid,   i, j, x, y) {
  x[0] = 0; x[1] = c0; x[2] = c1; x[3] = 1
  for (j = 0; j < 3; j++)
    for (i = 0; i < 3; i++)
      R(2, k, ox + x[i], ox + x[i + 1], oy + x[j], oy + x[j + 1], dir, (i == 1 && j == 1) ? mid : m)
}
# The four walls of the unit room at (ox, oy, oz), facing in.
function Walls(ox, oy, oz, m) {
  R(1, oy, ox, ox + 1, oz, oz + 1, 1, m)
  R(1, oy + 1, ox, ox + 1, oz, oz + 1, -1, m)
  R(0, ox, oy, oy + 1, oz, oz + 1, 1, m)
  R(0, ox + 1, oy, oy + 1, oz, oz + 1, -1, m)
}
function Mtl(name, kd, ke) { printf "newmtl %s\nKd %s\nKe %s\n\n", name, kd, ke > mtl }
BEGIN {
  if (scale == "") scale = 1
  if (n == "") n = 448
  if (sliver == "") sliver = 1e-4
  if (kd == "") kd = 0.5
  if (kd2 == "") kd2 = 0.8
  nv = 0; nf = 0; cur = ""
  name = mtl; sub(/.*\//, "", name)
  print "mtllib " name
  print "o " scene
  if (scene == "hdr") {
    Mtl("wall", "0.5", "0 0 0"); Mtl("bright", "0.5", "1e6 1e6 1e6"); Mtl("dim", "0.5", "1e-6 1e-6 1e-6")
    Grid(1, 0.495, 0.505, 0, 0, -1, "wall", "bright")
    Grid(0, 0.45, 0.55, 0, 0, 1, "wall", "dim")
    Walls(0, 0, 0, "wall")
  } else if (scene == "thin") {
    Mtl("wall", kd, "0 0 0"); Mtl("light", kd, "10 10 10"); Mtl("white", kd2, "0 0 0")
    Grid(1, 0.4, 0.6, 0, 0, -1, "wall", "light")
    R(2, 0, 0, 0.5, 0, 1, 1, "wall")
    R(2, 0, 0.5, 0.5 + sliver, 0, 1, 1, "wall")
    R(2, 0, 0.5 + sliver, 1, 0, 1, 1, "wall")
    Walls(0, 0, 0, "wall")
    R(1, 0.5, 0.2, 0.4, 0.2, 0.6, 1, "white"); R(1, 0.5, 0.2, 0.4, 0.2, 0.6, -1, "white")
    R(0, 0.8, 0.2, 0.4, -0.1, 0.3, 1, "white"); R(0, 0.8, 0.2, 0.4, -0.1, 0.3, -1, "white")
    R(2, 0, 0.1, 0.3, 0.6, 0.8, 1, "white")
    R(2, 0.3, 0.7, 0.701, 0.7, 0.701, 1, "white")
    # the cube [0,0.1]^3, facing out
    R(2, 0, 0, 0.1, 0, 0.1, -1, "white"); R(2, 0.1, 0, 0.1, 0, 0.1, 1, "white")
    R(1, 0, 0, 0.1, 0, 0.1, -1, "white"); R(1, 0.1, 0, 0.1, 0, 0.1, 1, "white")
    R(0, 0, 0, 0.1, 0, 0.1, -1, "white"); R(0, 0.1, 0, 0.1, 0, 0.1, 1, "white")
  } else if (scene == "leak") {
    Mtl("wall", "0.5", "0 0 0"); Mtl("light", "0.5", "10 10 10")
    # Room A: faces 0..8 ceiling (4 = light), 9 floor, 10..13 walls.
    Grid(1, 0.4, 0.6, 0, 0, -1, "wall", "light")
    R(2, 0, 0, 1, 0, 1, 1, "wall"); Walls(0, 0, 0, "wall")
    # Room B: faces 14 ceiling, 15 floor, 16..19 walls.
    R(2, 1, 1, 2, 0, 1, -1, "wall"); R(2, 0, 1, 2, 0, 1, 1, "wall"); Walls(1, 0, 0, "wall")
    # Room C: faces 20 ceiling, 21 floor, 22..25 walls.
    R(2, 2, 1, 2, 1, 2, -1, "wall"); R(2, 1, 1, 2, 1, 2, 1, "wall"); Walls(1, 1, 1, "wall")
  } else if (scene == "big") {
    Mtl("wall", "0.5", "0 0 0"); Mtl("light", "0.5", "10 10 10")
    R(2, 1, 0, 1, 0, 1, -1, "light")
    Walls(0, 0, 0, "wall")
    # The floor: (n+1)^2 shared points, n^2 quads.
    base = nv
    for (j = 0; j <= n; j++) for (i = 0; i <= n; i++) P(i / n, j / n, 0)
    print "usemtl wall"
    for (j = 0; j < n; j++)
      for (i = 0; i < n; i++) {
        a = base + 1 + j * (n + 1) + i
        print "f " a " " (a + 1) " " (a + n + 2) " " (a + n + 1)
      }
  } else {
    print "make_stiff.awk: unknown scene '" scene "'" > "/dev/stderr"
    exit 1
  }
}
