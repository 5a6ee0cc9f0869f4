#!/usr/bin/env python3
"""Writes data/parts/demo_housing.stl, the scanplan demo part: a cast and machined flanged
bearing / pump housing (binary little-endian STL, millimetres, base on z = 0, centred on the
z axis, 180 x 140 x 110 mm). Run from anywhere:

    python3 data/parts/make_demo_part.py

The part
  * base flange 180 x 140 x 16 with R20 corners, 1.5 mm edge chamfers and four chamfered
    through bolt holes (13.5 mm) on the corner centres;
  * round body (116 mm) up to z = 100, R8 fillet into the flange, two cast ribs (gussets, 10 mm)
    along x, chamfered top edge;
  * machined hub (92 mm) up to z = 110 with a 62 mm bearing seat, a 48 mm through bore and four
    blind M6 tap holes (5 x 12 mm, 118 deg drill point); cast recess (90 x 30 mm) underneath;
  * two port bosses (32 mm, R4 fillet, blind 14 mm ports) on +-y and two sensor bosses (20 mm,
    R3 fillet, blind 8.5 mm holes) on +-x, above the ribs.

Construction (closed, consistently oriented 2-manifold by construction; no booleans): the
body is a "generalised lathe", one closed counter-clockwise (r, z) profile per column, swept
around z, which gives a torus-like quad grid (genus 1: the bore). A hole or boss replaces a
block of grid quads by a patch: rays from the feature centre to the block boundary carry
loops that shrink onto the feature mouth, and the feature continues as a chain of loops (tube)
ending in a drill-point cone (blind hole) or in the matching patch on the other face of the
flange (through hole: +1 genus each, so genus 5). Every loop shares its vertices with its
neighbours, so every edge is used by exactly two triangles, in opposite directions.
Output is deterministic (no randomness, no timestamps).
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "demo_housing.stl")

# ---- dimensions (mm) -------------------------------------------------------------------------
FA, FB, FRC, FT, FCH = 90.0, 70.0, 20.0, 16.0, 1.5  # flange half length/width, corner R, thickness, chamfer
RB, ZB, FIL = 58.0, 100.0, 8.0                      # body radius, body top, flange fillet
RH, ZH = 46.0, 110.0                                # hub radius, hub top
RS, ZS, RBORE = 31.0, 92.0, 24.0                    # bearing seat radius / bottom, through bore radius
RR, ZR = 45.0, 30.0                                 # cast recess radius / height
RIBS, RIB_HW, RIB_GAP, RIB_FOOT, RIB_TOP = (0.0, math.pi), 5.0, 1.5, 84.0, 63.25
N_COLS = 160                                        # columns of the lathe grid (2.25 deg)
WALL_Z = [24.0, 29.0] + [34.0 + 3.25 * i for i in range(17)] + [89.0, 92.0, 95.0, 98.0]
S4 = (0.0, 0.25, 0.5, 0.75, 1.0)
TAN31 = math.tan(math.radians(31.0))                # 118 deg drill point: depth = r * tan(31 deg)

verts, tris, skip = [], [], set()


def vid(p):
    verts.append(p)
    return len(verts) - 1


def lerp(a, b, t):
    return a + (b - a) * t


def wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def quad(a, b, c, d):
    """Quad a-b-c-d, counter-clockwise seen from outside, split on its shorter diagonal."""
    if math.dist(verts[a], verts[c]) <= math.dist(verts[b], verts[d]):
        tris.extend(((a, b, c), (a, c, d)))
    else:
        tris.extend(((a, b, d), (b, c, d)))


def chain(loops):
    """Quad strips between consecutive loops (lists of equal length, same angular order)."""
    for p, q in zip(loops, loops[1:]):
        n = len(p)
        for i in range(n):
            quad(p[i], p[(i + 1) % n], q[(i + 1) % n], q[i])


def fan(loop, apex):
    n = len(loop)
    tris.extend((loop[i], loop[(i + 1) % n], apex) for i in range(n))


# ---- the lathe grid ------------------------------------------------------------------------
# A column is (theta, d): d None is the radial half-plane at angle theta; otherwise (ribs) it is
# the plane at lateral offset d from the rib's mid-plane outside the body (r >= RB), radial inside.
def col_angle(col, r):
    theta, d = col
    return theta if d is None else theta + math.asin(d / max(r, RB))


def col_point(col, r, z):
    a = col_angle(col, r)
    return (r * math.cos(a), r * math.sin(a), z)


def make_columns():
    step = 2.0 * math.pi / N_COLS
    edge = math.asin((RIB_HW + RIB_GAP) / RB) + 0.5 * step
    cols = [(i * step, None) for i in range(N_COLS) if min(abs(wrap(i * step - t)) for t in RIBS) > edge]
    for t in RIBS:
        for d in (-RIB_HW - RIB_GAP, -RIB_HW, -RIB_HW / 2, 0.0, RIB_HW / 2, RIB_HW, RIB_HW + RIB_GAP):
            cols.append((t, d))
    return sorted(cols, key=lambda c: col_angle(c, RB) % (2.0 * math.pi))


def outline_r(col, inset):
    """Distance along a column to the flange outline (rounded rectangle) shrunk by inset."""
    lo, hi = RB, 2.0 * FA
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        x, y, _ = col_point(col, mid, 0.0)
        qx, qy = abs(x) - (FA - FRC), abs(y) - (FB - FRC)
        sdf = math.hypot(max(qx, 0.0), max(qy, 0.0)) + min(max(qx, qy), 0.0) - FRC + inset
        lo, hi = (mid, hi) if sdf < 0.0 else (lo, mid)
    return lo


def profile(col):
    """Closed counter-clockwise (r, z) section along one column (same length for all columns)
    and the indices of named rings."""
    rib = col[1] is not None and abs(col[1]) <= RIB_HW
    ro, roc = outline_r(col, 0.0), outline_r(col, FCH)
    rin = RIB_FOOT if rib else RB + FIL
    slope = lambda z: RIB_FOOT - (z - 20.0) * (RIB_FOOT - RB) / (RIB_TOP - 20.0)
    arc = lambda cr, cz, rad, angs: [(cr + rad * math.cos(a), cz + rad * math.sin(a)) for a in angs]
    p, marks = [], {}

    def add(name, pts):
        marks[name] = len(p)
        p.extend(pts)

    add("under", [(RR + 1.0, 0.0), (0.5 * (RR + 1.0 + RB + FIL), 0.0)])
    add("flange_bottom", [(lerp(RB + FIL, roc, s), 0.0) for s in S4])  # mirrors flange_top
    add("rim", [(ro, FCH), (ro, FT - FCH)])
    add("flange_top", [(lerp(rin, roc, s), FT) for s in reversed(S4)])
    if rib:  # end face, then the sloped top, which meets the body wall at RIB_TOP
        add("junction", [(RIB_FOOT, 18.0), (RIB_FOOT, 20.0), (slope(21.5), 21.5), (slope(23.0), 23.0)])
    else:
        add("junction", arc(RB + FIL, FT + FIL, FIL, [-math.pi / 2 * (1 + i / 5) for i in range(1, 5)]))
    add("wall", [(max(RB, slope(z)) if rib else RB, z) for z in WALL_Z])
    add("top", [(RB - 2.0, ZB), (RH + 3.0, ZB)] + arc(RH + 3.0, ZB + 3.0, 3.0, (-2 * math.pi / 3, -5 * math.pi / 6)))
    add("hub", [(RH, ZB + 3.0), (RH, ZH - 1.5)])
    add("hub_top", [(lerp(RH - 1.5, RS + 1.0, s), ZH) for s in S4])
    add("seat", [(RS, ZH - 1.0), (RS, 100.5), (RS, ZS), (RBORE + 0.5, ZS), (RBORE, ZS - 0.5)])
    add("bore", [(RBORE, lerp(ZS - 0.5, ZR + 0.5, s)) for s in S4[1:]])
    add("recess", [(RBORE + 0.5, ZR), (32.0, ZR), (RR - 5.0, ZR)] + arc(RR - 5.0, ZR - 5.0, 5.0, (math.pi / 3, math.pi / 6))
        + [(RR, ZR - 5.0), (RR, 17.0), (RR, 9.0), (RR, 1.0)])
    return p, marks


cols = make_columns()
N = len(cols)
profiles = [profile(c) for c in cols]
marks = profiles[0][1]
K = len(profiles[0][0])
grid = [[vid(col_point(cols[j], *profiles[j][0][k])) for j in range(N)] for k in range(K)]


# ---- feature patches -----------------------------------------------------------------------
def block(ka, kb, theta, half):
    """Reserve grid rings ka..kb x the radial columns nearest theta -+ half; return the block's
    boundary cells (k, j), counter-clockwise in (j, k) like the grid quads."""
    near = lambda t: min((j for j in range(N) if cols[j][1] is None), key=lambda j: abs(wrap(cols[j][0] - t)))
    ja, jb = near(theta - half), near(theta + half)
    jb += N if jb < ja else 0
    for k in range(ka, kb):
        for j in range(ja, jb):
            assert (k, j % N) not in skip, "overlapping feature patches"
            skip.add((k, j % N))
    return ([(ka, j) for j in range(ja, jb)] + [(k, jb) for k in range(ka, kb)]
            + [(kb, j) for j in range(jb, ja, -1)] + [(k, ja) for k in range(kb, ka, -1)])


def ids_of(cells, kmap=lambda k: k):
    return [grid[kmap(k)][j % N] for k, j in cells]


def rays(ids, to_uv):
    """Angles (in the face chart, about the feature centre) of the block boundary vertices."""
    return [math.atan2(v, u) for u, v in (to_uv(verts[i]) for i in ids)]


def ring(angs, f):
    return [vid(f(a)) for a in angs]


def shrink(ids, mouth, to_uv, from_uv, fracs=(0.55, 0.22)):
    """Loops from the block boundary (ids) to the feature mouth along the rays, outermost first."""
    outer, inner = [to_uv(verts[i]) for i in ids], [to_uv(verts[i]) for i in mouth]
    return [ids] + [[vid(from_uv(lerp(m[0], o[0], t), lerp(m[1], o[1], t))) for o, m in zip(outer, inner)]
                    for t in fracs] + [mouth]


def flat(cx, cy, z0):
    """Chart of the plane z = z0 about (cx, cy), and circle points on it."""
    return (lambda p: (p[0] - cx, p[1] - cy)), (lambda u, v: (cx + u, cy + v, z0))


def circle(cx, cy, rho, z):
    return lambda a: (cx + rho * math.cos(a), cy + rho * math.sin(a), z)


def flange_hole(cx, cy, half, r=6.75, ch=1.0):
    """Chamfered through hole in the flange: top patch, bore, bottom patch as one chain."""
    theta, kt, kb = math.atan2(cy, cx), marks["flange_top"], marks["flange_bottom"]
    cells = block(kt, kt + 4, theta, half)
    block(kb, kb + 4, theta, half)  # same columns; its ring kb + 4 - i lies under top ring kt + i
    top, bot = ids_of(cells), ids_of(cells, lambda k: kb + 4 - (k - kt))
    angs = rays(top, flat(cx, cy, FT)[0])
    bore = [ring(angs, circle(cx, cy, r, FT - ch)), ring(angs, circle(cx, cy, r, ch))]
    upper = shrink(top, ring(angs, circle(cx, cy, r + ch, FT)), *flat(cx, cy, FT))
    lower = shrink(bot, ring(angs, circle(cx, cy, r + ch, 0.0)), *flat(cx, cy, 0.0))
    chain(upper + bore + lower[::-1])


def hub_hole(theta, rc=38.25, half=math.radians(15), r=2.5, depth=12.0):
    """Blind tap-drill hole in the hub top: chamfer, bore, drill-point cone."""
    cx, cy, k = rc * math.cos(theta), rc * math.sin(theta), marks["hub_top"]
    ids = ids_of(block(k, k + 4, theta, half))
    angs = rays(ids, flat(cx, cy, ZH)[0])
    loops = shrink(ids, ring(angs, circle(cx, cy, r + 0.5, ZH)), *flat(cx, cy, ZH))
    loops += [ring(angs, circle(cx, cy, r, ZH - 0.5)), ring(angs, circle(cx, cy, r, ZH - depth))]
    chain(loops)
    fan(loops[-1], vid((cx, cy, ZH - depth - r * TAN31)))


def boss(theta, z_lo, z_hi, half, rb, fil, x_face, r_hole, depth, ch):
    """Radial boss on the body wall (wall rings z_lo..z_hi, centred between them): fillet foot,
    chamfered face, blind chamfered hole with drill point. Local frame: x radial, y tangential."""
    ka, kb = marks["wall"] + WALL_Z.index(z_lo), marks["wall"] + WALL_Z.index(z_hi)
    zc, c, s = 0.5 * (z_lo + z_hi), math.cos(theta), math.sin(theta)
    to_uv = lambda p: (RB * wrap(math.atan2(p[1], p[0]) - theta), p[2] - zc)
    from_uv = lambda u, v: (RB * math.cos(theta + u / RB), RB * math.sin(theta + u / RB), zc + v)
    on_body = lambda y, t: math.sqrt(RB * RB - y * y) + t

    def at(rho, x):  # x(y): local radial position of the ring point at lateral offset y
        def f(a):
            y, z = rho * math.cos(a), rho * math.sin(a)
            xx = x(y)
            return (xx * c - y * s, xx * s + y * c, zc + z)
        return f

    ids = ids_of(block(ka, kb, theta, half))
    angs = rays(ids, to_uv)
    foot = [at(rb + fil * (1 - math.sin(b)), lambda y, b=b: on_body(y, fil * (1 - math.cos(b))))
            for b in (math.pi / 2 * m / 3 for m in range(4))]
    tube = [at(rb, lambda y, t=t: lerp(on_body(y, fil), x_face - ch, t)) for t in (1 / 3, 2 / 3, 1.0)]
    face = [at(rho, lambda y, x=x: x) for rho, x in ((rb - ch, x_face), (0.5 * (rb - ch + r_hole + ch), x_face),
                                                    (r_hole + ch, x_face), (r_hole, x_face - ch),
                                                    (r_hole, x_face - depth))]
    loops = shrink(ids, ring(angs, foot[0]), to_uv, from_uv)
    loops += [ring(angs, f) for f in foot[1:] + tube + face]
    chain(loops)
    tip = x_face - depth - r_hole * TAN31
    fan(loops[-1], vid((tip * c, tip * s, zc)))


for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
    flange_hole(sx * (FA - FRC), sy * (FB - FRC), math.radians(22))
for i in range(4):
    hub_hole(math.radians(45 + 90 * i))
for th in (math.pi / 2, -math.pi / 2):  # ports
    boss(th, 34.0, 86.0, math.radians(26), 16.0, 4.0, 70.0, 7.0, 18.0, 1.0)
for th in RIBS:  # sensor bosses above the ribs
    boss(th, RIB_TOP, 98.0, math.radians(18), 10.0, 3.0, 68.0, 4.25, 14.0, 0.75)
for k in range(K):
    for j in range(N):
        if (k, j) not in skip:
            quad(grid[k][j], grid[k][(j + 1) % N], grid[(k + 1) % K][(j + 1) % N], grid[(k + 1) % K][j])


def write_binary_stl(path):
    with open(path, "wb") as f:
        f.write(b"scanplan demo part: flanged housing, mm".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            a, b, c = (verts[i] for i in t)
            u = [b[i] - a[i] for i in range(3)]
            v = [c[i] - a[i] for i in range(3)]
            n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
            ln = math.hypot(*n) or 1.0
            f.write(struct.pack("<12fH", *(x / ln for x in n), *a, *b, *c, 0))


if __name__ == "__main__":
    write_binary_stl(OUT)
    print(f"wrote {OUT}: {len(tris)} triangles")
