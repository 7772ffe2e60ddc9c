#!/usr/bin/env python3
"""Generates csgvox's ground-truth parts: data/<part>/tree.json and data/README.md.

Every part is a CSG tree of a real mechanical part, in millimetres, written in
csgvox's tree.json format (see io/tree_json.cpp). The script is deterministic
and uses the Python standard library only.

Besides writing the trees, it checks every part:
  * parameters: unit axes, right-handed orthonormal box frames, positive sizes,
    cone radii >= 0 and not both 0, torus minor <= major, unique leaf names;
  * off-axis parts: no box axis, cylinder/cone/torus axis or half-space normal
    within 5 degrees of a world axis;
  * Monte-Carlo (stratified, ~20000 points in the solid's bounding box grown
    by 2 mm): every
    leaf changes the classification of >= 0.1 % of the points when it is
    removed (replaced by the empty set in a union or a difference's first
    operand, skipped in an intersection or a later difference operand);
  * surfaces: no two primitives have parallel surface patches closer than 1 mm
    (this catches coincident faces, unions that only touch, and holes that do
    not clear the face they cut), apart from tangencies listed by the part
    (fillet tori, slot ends);
  * thinness, informational: at 64 voxels along the longest side, the share
    of solid (and empty) voxels that no 2x2x2 block of solid (empty) voxels
    covers.

Usage: python3 data/make_parts.py [--out DIR] [--points N] [--no-readme]
"""

import argparse
import json
import math
import os
import random
import sys
import zlib

# ----------------------------------------------------------------------------
# Small vector helpers (3-tuples of floats).

def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def unit(a):
    n = norm(a)
    if n == 0.0:
        raise ValueError("zero vector")
    return (a[0] / n, a[1] / n, a[2] / n)


def vec(a):
    return (float(a[0]), float(a[1]), float(a[2]))


def mat_vec(m, v):
    """m is a tuple of three rows."""
    return (dot(m[0], v), dot(m[1], v), dot(m[2], v))


def rotation(axis, degrees):
    """Rotation matrix (rows) of `degrees` about `axis` (Rodrigues)."""
    x, y, z = unit(axis)
    t = math.radians(degrees)
    c, s = math.cos(t), math.sin(t)
    C = 1.0 - c
    return ((c + x * x * C, x * y * C - z * s, x * z * C + y * s),
            (y * x * C + z * s, c + y * y * C, y * z * C - x * s),
            (z * x * C - y * s, z * y * C + x * s, c + z * z * C))


def perpendicular_frame(axis):
    """Two unit vectors u, v with (u, v, axis) right-handed orthonormal."""
    a = unit(axis)
    helper = (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0)
    u = unit(cross(helper, a))
    v = cross(a, u)
    return u, v


X = (1.0, 0.0, 0.0)
Y = (0.0, 1.0, 0.0)
Z = (0.0, 0.0, 1.0)
IDENTITY = (X, Y, Z)

# ----------------------------------------------------------------------------
# Node constructors, producing the JSON objects of tree.json directly (key
# order as csgvox writes them).

def box(name, center, half_size, axes=IDENTITY):
    return {"type": "box", "name": name, "center": vec(center),
            "axes": [vec(a) for a in axes], "half_size": vec(half_size)}


def box_span(name, lo, hi, axes=IDENTITY):
    """Axis-aligned box from its min and max corners."""
    center = scale(add(lo, hi), 0.5)
    half = scale(sub(hi, lo), 0.5)
    return box(name, center, half, axes)


def cylinder(name, center, axis, radius, height):
    return {"type": "cylinder", "name": name, "center": vec(center), "axis": vec(unit(axis)),
            "radius": float(radius), "height": float(height)}


def cylinder_between(name, p0, p1, radius):
    """Cylinder whose axis segment runs from p0 to p1."""
    d = sub(p1, p0)
    return cylinder(name, scale(add(p0, p1), 0.5), d, radius, norm(d))


def cone_between(name, bottom, top, radius_bottom, radius_top):
    """Cone frustum from the bottom cap centre to the top cap centre."""
    d = sub(top, bottom)
    return {"type": "cone", "name": name, "center": vec(scale(add(bottom, top), 0.5)),
            "axis": vec(unit(d)), "radius_bottom": float(radius_bottom),
            "radius_top": float(radius_top), "height": float(norm(d))}


def sphere(name, center, radius):
    return {"type": "sphere", "name": name, "center": vec(center), "radius": float(radius)}


def torus(name, center, axis, major_radius, minor_radius):
    return {"type": "torus", "name": name, "center": vec(center), "axis": vec(unit(axis)),
            "major_radius": float(major_radius), "minor_radius": float(minor_radius)}


def halfspace(name, normal, point):
    """The half-space {x : n.x <= n.point}, n = unit(normal) pointing outwards."""
    n = unit(normal)
    return {"type": "halfspace", "name": name, "normal": vec(n), "offset": float(dot(n, point))}


def union(*children):
    return {"op": "union", "children": list(children)}


def intersection(*children):
    return {"op": "intersection", "children": list(children)}


def difference(*children):
    return {"op": "difference", "children": list(children)}


def complement(child):
    return {"op": "complement", "children": [child]}


def transformed(node, rot, shift=(0.0, 0.0, 0.0)):
    """The tree moved by x -> rot*x + shift (rot a rotation matrix, rows)."""
    if "op" in node:
        kids = [transformed(c, rot, shift) for c in node["children"]]
        return {"op": node["op"], "children": kids}
    out = dict(node)
    if "center" in out:
        out["center"] = vec(add(mat_vec(rot, out["center"]), shift))
    if "axis" in out:
        out["axis"] = vec(mat_vec(rot, out["axis"]))
    if "axes" in out:
        out["axes"] = [vec(mat_vec(rot, a)) for a in out["axes"]]
    if "normal" in out:
        n = vec(mat_vec(rot, out["normal"]))
        out["normal"] = n
        out["offset"] = float(out["offset"] + dot(n, shift))
    return out


def leaves(node):
    if "op" in node:
        for c in node["children"]:
            yield from leaves(c)
    else:
        yield node


def operation_count(node):
    if "op" not in node:
        return 0
    return 1 + sum(operation_count(c) for c in node["children"])


def depth(node):
    if "op" not in node:
        return 1
    return 1 + max(depth(c) for c in node["children"])

# ----------------------------------------------------------------------------
# The parts. Each returns a dict: root, title, description, features,
# tangent (pairs of leaf names whose surfaces touch tangentially by design),
# off_axis (True when no primitive may be axis-aligned).


def part_plate_holes():
    t = 8.0
    hole_z0, hole_z1 = -2.0, t + 2.0
    holes = [cylinder_between(f"hole_{i + 1}", (x, y, hole_z0), (x, y, hole_z1), 5.0)
             for i, (x, y) in enumerate([(-38, -20), (38, -20), (38, 20), (-38, 20)])]
    root = difference(box_span("plate", (-50, -30, 0), (50, 30, t)), *holes)
    return dict(
        root=root,
        title="Plate with four through holes",
        description="Mounting plate 100 x 60 x 8 with four 10 mm through holes on a 76 x 40 "
                    "pattern.",
        features="box; cylinders subtracted in one flat n-ary difference; through holes "
                 "(tools stick out 2 mm on both faces)",
        thinnest="5 mm ligament between the holes and the long edges")


def part_l_bracket():
    t = 8.0  # thickness of both legs
    block = box_span("block", (0, -20, 0), (70, 20, 55))
    inner_cut = box_span("inner_cut", (t, -23, t), (73, 23, 58))
    # Removes the outer bend edge: the half-space x + z <= 8 (its outward normal
    # points into the bracket; the difference keeps the other side).
    chamfer = halfspace("chamfer", (1, 0, 1), (8, 0, 0))
    r = 4.5
    base_holes = [cylinder_between(f"base_hole_{i + 1}", (45, y, -2), (45, y, t + 2), r)
                  for i, y in enumerate((-10.0, 10.0))]
    leg_holes = [cylinder_between(f"leg_hole_{i + 1}", (-2, y, 36), (t + 2, y, 36), r)
                 for i, y in enumerate((-10.0, 10.0))]
    root = difference(block, inner_cut, chamfer, *base_holes, *leg_holes)
    return dict(
        root=root,
        title="L bracket",
        description="Angle bracket 70 x 40 x 55, legs 8 mm thick, made as a block minus the "
                    "inner corner box; the outer bend edge carries an 8 mm 45-degree chamfer "
                    "(half-space); two 9 mm holes in each leg, one pair vertical and one pair "
                    "horizontal.",
        features="two boxes (L by subtraction, so no coplanar union faces); half-space chamfer "
                 "subtracted; holes along two different axes",
        thinnest="5.5 mm ligament between the holes and the side faces (5.7 mm across the "
                 "chamfered bend)")


def part_flange():
    disk_t = 12.0
    hub_r, hub_top = 25.0, 37.0
    f = 6.0  # fillet radius hub/disk
    disk = cylinder_between("disk", (0, 0, 0), (0, 0, disk_t), 50.0)
    hub = cylinder_between("hub", (0, 0, disk_t - 4), (0, 0, hub_top), hub_r)
    fillet_ring = cylinder_between("fillet_ring", (0, 0, disk_t - 2), (0, 0, disk_t + f), hub_r + f)
    fillet_torus = torus("fillet_torus", (0, 0, disk_t + f), Z, hub_r + f, f)
    bore = cylinder_between("bore", (0, 0, -2), (0, 0, hub_top + 2), 15.0)
    pcd_r = 38.0
    bolt_holes = []
    for i in range(6):
        a = math.radians(60.0 * i + 30.0)
        x, y = pcd_r * math.cos(a), pcd_r * math.sin(a)
        bolt_holes.append(
            cylinder_between(f"bolt_hole_{i + 1}", (x, y, -2), (x, y, disk_t + 2), 5.0))
    root = difference(union(disk, hub, difference(fillet_ring, fillet_torus)), bore, *bolt_holes)
    return dict(
        root=root,
        title="Hub flange",
        description="Hub flange: disk 100 x 12 with a 50 mm hub 25 mm high, 30 mm "
                    "through bore, 6 mm concave fillet between hub and disk, six 10 mm bolt "
                    "holes on a 76 mm pitch circle.",
        features="coaxial cylinders; concave fillet = ring cylinder minus torus (nested "
                 "difference inside a union); six holes on a bolt circle (non-axis-aligned "
                 "positions)",
        thinnest="7 mm between the bolt holes and the rim",
        tangent=[("fillet_torus", "disk"), ("fillet_torus", "hub")])


def part_pipe_tee():
    run_outer = cylinder_between("run_outer", (-55, 0, 0), (55, 0, 0), 22.0)
    run_bore = cylinder_between("run_bore", (-57, 0, 0), (57, 0, 0), 15.0)
    branch_outer = cylinder_between("branch_outer", (0, 0, 0), (0, 0, 50), 18.0)
    branch_bore = cylinder_between("branch_bore", (0, 0, 3), (0, 0, 53), 11.0)
    local = difference(union(run_outer, branch_outer), run_bore, branch_bore)
    rot = rotation((0.3, -1.0, 0.6), 35.0)
    root = transformed(local, rot, (5.0, -3.0, 10.0))
    return dict(
        root=root,
        title="Reducing pipe tee (off-axis)",
        description="Reducing tee: run 44 OD / 30 ID x 110 long, branch 36 OD / 22 ID rising 50 "
                    "mm from the run axis; walls 7 mm. The whole part is rotated 35 degrees "
                    "about (0.3, -1, 0.6) and shifted, so no axis is aligned with the world.",
        features="crossing cylinders of different radii; bores meet inside the part; "
                 "arbitrary pose",
        thinnest="7 mm walls",
        off_axis=True)


def part_stepped_shaft():
    c = 4.0  # 45-degree end chamfers
    # Sections along +x; each smaller section reaches 1.5 mm into its larger
    # neighbour so no two end faces coincide.
    journal = cylinder_between("journal", (0, 0, 0), (31.5, 0, 0), 12.0)
    collar = cylinder_between("collar", (30, 0, 0), (42, 0, 0), 21.0)
    main = cylinder_between("main", (40.5, 0, 0), (85, 0, 0), 16.0)
    end = cylinder_between("end", (83.5, 0, 0), (120, 0, 0), 12.0)
    # Chamfer cones: radius r - c at the end face, growing 1 mm per mm; they
    # start 1.5 mm outside the end face and run past the section's inner end.
    r0 = 12.0 - c - 1.5
    chamfer_left = cone_between("chamfer_left", (-1.5, 0, 0), (33, 0, 0), r0, r0 + 34.5)
    chamfer_right = cone_between("chamfer_right", (121.5, 0, 0), (82, 0, 0), r0, r0 + 39.5)
    keyway = box_span("keyway", (90, -4, 12.0 - 4.5), (110, 4, 14))
    pin_hole = cylinder_between("pin_hole", (63, -18, 0), (63, 18, 0), 4.0)
    root = difference(
        union(intersection(journal, chamfer_left), collar, main, intersection(end, chamfer_right)),
        keyway, pin_hole)
    return dict(
        root=root,
        title="Stepped shaft",
        description="Turned shaft 120 long: 24 mm journal, 42 mm collar, 32 mm main body with an "
                    "8 mm cross pin hole, 24 mm end with a closed 8 x 20 x 4.5 keyway; 4 mm "
                    "45-degree chamfers at both ends.",
        features="coaxial cylinders of four diameters overlapping along the axis; chamfers as "
                 "intersection with cones (one cone axis reversed); keyway box; radial cross "
                 "hole; shaft axis along x",
        thinnest="4.5 mm keyway depth; 5 mm radial collar step")


def part_knob():
    body_r = 25.0
    edge_z, apex_z = 26.0, 34.0
    # Dome sphere through the rim (r=25 at z=26) and the apex (0, 0, 34).
    zc = (body_r ** 2 + edge_z ** 2 - apex_z ** 2) / (2.0 * (edge_z - apex_z))
    dome_r = apex_z - zc
    body = cylinder_between("body", (0, 0, 0), (0, 0, apex_z + 2), body_r)
    dome = sphere("dome", (0, 0, zc), dome_r)
    groove = torus("grip_groove", (0, 0, 16), Z, body_r + 4.5 - 3.5, 4.5)
    bore = cylinder_between("bore", (0, 0, -2), (0, 0, 20), 6.0)
    bore_flat = box_span("bore_flat", (2.5, -8, -4), (9, 8, 22))
    set_screw = cylinder_between("set_screw", (0, 0, 6), (body_r + 2, 0, 6), 2.5)
    local = difference(intersection(body, dome), groove, difference(bore, bore_flat), set_screw)
    rot = rotation((2.0, -1.0, 1.0), 28.0)
    root = transformed(local, rot, (12.0, -8.0, 5.0))
    return dict(
        root=root,
        title="Control knob (off-axis)",
        description="Knob 50 mm across, 34 high: cylinder with a spherical domed top, a "
                    "half-round grip groove (torus), a 12 mm D-bore 20 deep (bore minus a flat) "
                    "and a 5 mm radial set-screw hole onto the flat. Tilted 28 degrees about "
                    "(2, -1, 1) and shifted.",
        features="intersection cylinder/sphere (spherical cap); torus groove subtracted; nested "
                 "difference for the D-bore tool; blind holes; arbitrary pose",
        thinnest="3 mm between the set-screw hole and the grip groove (3.5 mm to the bottom "
                 "face, 3.5 mm deep D flat)",
        off_axis=True)


def part_bearing_housing():
    half_w, flange_t = 43.0, 14.0
    boss_r, boss_top = 32.0, 40.0
    c = 3.0  # chamfer on the boss top edge
    f = 6.0  # fillet boss/flange
    flange = box_span("flange", (-half_w, -half_w, 0), (half_w, half_w, flange_t))
    boss_z0 = flange_t - 4
    boss = cylinder_between("boss", (0, 0, boss_z0), (0, 0, boss_top), boss_r)
    # 45-degree cone: radius boss_r - c at the top face, 1 mm more per mm down;
    # it spans the boss with 2 mm (bottom) and 1 mm (top) to spare.
    cone_z0 = boss_z0 - 2
    boss_chamfer = cone_between("boss_chamfer", (0, 0, cone_z0), (0, 0, boss_top + 1),
                                boss_r - c + (boss_top - cone_z0), boss_r - c - 1)
    fillet_ring = cylinder_between("fillet_ring", (0, 0, flange_t - 2), (0, 0, flange_t + f),
                                   boss_r + f)
    fillet_torus = torus("fillet_torus", (0, 0, flange_t + f), Z, boss_r + f, f)
    seat = sphere("seat", (0, 0, 26), 24.0)
    bore = cylinder_between("bore", (0, 0, -2), (0, 0, boss_top + 3), 15.0)
    bolt_holes = [cylinder_between(f"bolt_hole_{i + 1}", (x, y, -2), (x, y, flange_t + 2), 5.5)
                  for i, (x, y) in enumerate([(-32, -32), (32, -32), (32, 32), (-32, 32)])]
    root = difference(
        union(flange, intersection(boss, boss_chamfer), difference(fillet_ring, fillet_torus)),
        seat, bore, *bolt_holes)
    return dict(
        root=root,
        title="Flanged bearing housing",
        description="Square-flange bearing unit (UCF style): flange 86 x 86 x 14 with four 11 mm "
                    "bolt holes, boss 64 mm in diameter, 40 mm high overall, with a 3 mm top "
                    "chamfer (cone) and a 6 mm fillet to the flange (ring minus torus), "
                    "spherical bearing seat (sphere R24) and a 30 mm through bore.",
        features="box + cylinder union; torus fillet ring; cone chamfer by intersection; "
                 "sphere subtracted as a spherical seat; bolt pattern",
        thinnest="5.5 mm between the bolt holes and the flange edges; 8 mm seat wall",
        tangent=[("fillet_torus", "flange"), ("fillet_torus", "boss")])


def part_rotated_block():
    block = box("block", (0, 0, 0), (40, 25, 12.5))
    hole = cylinder_between("hole", (-22, 0, -15), (-22, 0, 15), 8.0)
    slot_box = box_span("slot_box", (6, -6, -15), (26, 6, 15))
    slot_end_1 = cylinder_between("slot_end_1", (6, 0, -15), (6, 0, 15), 6.0)
    slot_end_2 = cylinder_between("slot_end_2", (26, 0, -15), (26, 0, 15), 6.0)
    rebate = box_span("rebate", (-42, 15, 2.5), (42, 27, 14.5))
    local = difference(block, hole, slot_box, slot_end_1, slot_end_2, rebate)
    rot = rotation((1.0, 2.0, 3.0), 25.0)
    root = transformed(local, rot, (20.0, -10.0, 15.0))
    return dict(
        root=root,
        title="Rotated block with hole, slot and rebate",
        description="Block 80 x 50 x 25 with a 16 mm through hole, a 12 mm wide obround through "
                    "slot (box + two end cylinders, 32 long overall) and a 10 x 10 rebate along "
                    "one top edge; the whole part is rotated 25 degrees about (1, 2, 3)/sqrt(14) "
                    "and shifted by (20, -10, 15).",
        features="oriented boxes (non-identity frames); obround slot from a box and two "
                 "tangent cylinders; rebate step; arbitrary pose",
        thinnest="7 mm between the hole and the rebate",
        tangent=[("slot_box", "slot_end_1"), ("slot_box", "slot_end_2")],
        off_axis=True)


def part_housing_complex():
    base_t = 14.0
    base = box_span("base", (-60, -40, 0), (60, 40, base_t))
    b1, b2 = (-25.0, 0.0), (28.0, 0.0)
    boss_1 = cylinder_between("boss_1", (b1[0], b1[1], base_t - 4), (b1[0], b1[1], 38), 17.0)
    boss_2 = cylinder_between("boss_2", (b2[0], b2[1], base_t - 4), (b2[0], b2[1], 30), 14.0)
    rib = box_span("rib", (-11, -3.5, base_t - 2), (17, 3.5, 26))
    gusset = box_span("gusset", (b1[0] - 3.5, -35, base_t - 2), (b1[0] + 3.5, 35, 34))
    # Gusset top slopes from z=32 at |y|=17 (boss surface) to z=20 at |y|=35.
    k = 12.0 / 18.0
    gusset_slope_1 = halfspace("gusset_slope_1", (0, k, 1), (0, 17, 32))
    gusset_slope_2 = halfspace("gusset_slope_2", (0, -k, 1), (0, -17, 32))
    bore_1 = cylinder_between("bore_1", (b1[0], b1[1], -2), (b1[0], b1[1], 40), 10.0)
    bore_2 = cylinder_between("bore_2", (b2[0], b2[1], -2), (b2[0], b2[1], 32), 7.5)
    corners = [(-45.5, -25.5), (45.5, -25.5), (45.5, 25.5), (-45.5, 25.5)]
    mount_holes = [cylinder_between(f"mount_hole_{i + 1}", (x, y, -2), (x, y, 12), 5.5)
                   for i, (x, y) in enumerate(corners)]
    cbores = [cylinder_between(f"cbore_{i + 1}", (x, y, 8), (x, y, base_t + 2), 9.5)
              for i, (x, y) in enumerate(corners)]
    root = difference(
        union(base, boss_1, boss_2, rib,
              intersection(gusset, gusset_slope_1, gusset_slope_2)),
        bore_1, bore_2, *mount_holes, *cbores)
    return dict(
        root=root,
        title="Gearbox housing base",
        description="Base plate 120 x 80 x 14 carrying two bearing bosses (34 mm and 28 mm, "
                    "bores 20 and 15 mm) joined by a 7 mm rib, a 7 mm gusset across the large "
                    "boss with 34-degree sloped tops, and four M10 counterbored mounting holes "
                    "(11 mm through, 19 mm x 6 mm counterbores).",
        features="17 primitives; n-ary union of plate, bosses, rib and a sloped gusset "
                 "(box intersected with two half-spaces); bores through boss and plate; "
                 "counterbores (coaxial cylinder pairs)",
        thinnest="5 mm between the counterbores and the plate edges; 6 mm tall gusset ends")


def part_wedge_block():
    block = box_span("block", (0, -25, 0), (80, 25, 40))
    # Ramp: flat top for x <= 20, then down to z=16 at x=80 (slope 0.4).
    slope = halfspace("slope", (0.4, 0, 1), (20, 0, 40))
    bevel = halfspace("bevel", (1, 1, 0), (80 - 12, 25, 0))
    root = intersection(block, slope, bevel)
    return dict(
        root=root,
        title="Wedge block",
        description="Ramp block 80 x 50 x 40: flat top for 20 mm, then a 21.8-degree slope down "
                    "to 16 mm at the far end, one vertical edge bevelled 12 x 12 at 45 degrees.",
        features="box intersected with two oblique half-spaces (one sloped, one vertical)",
        thinnest="16 mm at the low end of the ramp")


def part_countersunk_plate():
    t = 10.0
    plate = box_span("plate", (-50, -35, 0), (50, 35, t))
    corners = [(-36, -21), (36, -21), (36, 21), (-36, 21)]
    holes = [cylinder_between(f"hole_{i + 1}", (x, y, -2), (x, y, t + 4), 4.5)
             for i, (x, y) in enumerate(corners)]
    # 90-degree countersinks, 18 mm at the top face: cone with apex at z=1.
    csks = [cone_between(f"countersink_{i + 1}", (x, y, 1), (x, y, t + 2), 0.0, t + 1)
            for i, (x, y) in enumerate(corners)]
    center_bore = cylinder_between("center_bore", (0, 0, -4), (0, 0, t + 4), 10.0)
    # 3 mm 45-degree chamfers on both ends of the centre bore.
    chamfer_top = cone_between("bore_chamfer_top", (0, 0, 6), (0, 0, t + 2), 9.0, 15.0)
    chamfer_bottom = cone_between("bore_chamfer_bottom", (0, 0, -2), (0, 0, 4), 15.0, 9.0)
    root = difference(plate, *holes, *csks, center_bore, chamfer_top, chamfer_bottom)
    return dict(
        root=root,
        title="Countersunk plate",
        description="Cover plate 100 x 70 x 10 with four 9 mm holes countersunk 90 degrees to "
                    "18 mm (M8 flat heads) and a 20 mm centre bore chamfered 3 mm on both faces.",
        features="pointed cones (radius 0 at the apex) and frustums of both orientations; "
                 "12-operand flat difference",
        thinnest="5 mm between the countersinks and the plate edges")


def part_funnel():
    k = 32.0 / 45.0          # radius growth per mm of the bowl cone
    wall = 6.0               # wall thickness, normal to the cone
    dr = wall * math.sqrt(1.0 + k * k)  # the same wall measured radially
    r_out = lambda z: 12.0 + k * (z - 30.0)
    r_in = lambda z: r_out(z) - dr
    spout = cylinder_between("spout", (0, 0, 0), (0, 0, 32), 12.0)
    bowl = cone_between("bowl", (0, 0, 28), (0, 0, 75), r_out(28), r_out(75))
    rim = torus("rim", (0, 0, 75), Z, 40.5, 5.5)
    bowl_inner = cone_between("bowl_inner", (0, 0, 26), (0, 0, 84), r_in(26), r_in(84))
    spout_bore = cylinder_between("spout_bore", (0, 0, -2), (0, 0, 40), 6.0)
    root = difference(union(spout, bowl, rim), bowl_inner, spout_bore)
    return dict(
        root=root,
        title="Funnel",
        description="Moulded funnel: conical bowl 88 mm across, flaring at 35 degrees to the "
                    "axis, with 6 mm walls, rounded bead rim (torus), 24 mm spout with a 12 mm "
                    "bore, 80.5 mm tall.",
        features="cone shell (outer minus inner cone); torus bead unioned then trimmed by the "
                 "inner cone; spout cylinder",
        thinnest="6 mm walls (bowl, normal to the cone, and spout)")


# ----------------------------------------------------------------------------
# Thin-feature parts (data/thin/): features at or below a voxel at res 64,
# which only the points can show.

def part_slotted_plate():
    plate = box_span("plate", (-30, -20, 0), (30, 20, 8))
    slot = box_span("slot", (-0.3, -12, -2), (0.3, 12, 10))
    hole = cylinder_between("hole", (18, 0, -2), (18, 0, 10), 5.0)
    return dict(
        root=difference(plate, slot, hole),
        title="Plate with a saw cut",
        description="Plate 60 x 40 x 8 with a 0.6 mm wide, 24 mm long through saw cut (a voxel is "
                    "0.97 mm at res 64) and a 10 mm hole.",
        features="slot narrower than a voxel",
        thinnest="0.6 mm slot")


def part_thin_tray():
    outer = box_span("outer", (-30, -20, 0), (30, 20, 20))
    inner = box_span("inner", (-29, -19, 1), (29, 19, 22))
    return dict(
        root=difference(outer, inner),
        title="Open tray with 1 mm walls",
        description="Open box 60 x 40 x 20 with 1 mm walls and floor (a voxel is 0.97 mm at "
                    "res 64).",
        features="walls one voxel thick",
        thinnest="1 mm walls",
        tangent=[("outer", "inner")])


def part_pin_base():
    base = box_span("base", (-15, -15, 0), (15, 15, 5))
    pin = cylinder_between("pin", (0, 0, 4), (0, 0, 47), 1.0)
    tip = cone_between("tip", (0, 0, 45), (0, 0, 52), 3.5, 0.0)
    return dict(
        root=union(base, pin, tip),
        title="Base with a thin pin and a conical tip",
        description="Base 30 x 30 x 5 with a 2 mm pin 40 mm long ending in a 7 mm cone "
                    "(a spike head, 7 mm across at its base; a voxel is 0.8 mm at res 64).",
        features="thin rod (2.6 voxels across) with a cone end",
        thinnest="2 mm pin")


def part_sheet_bracket():
    t = 1.5
    base = box_span("base", (-30, -20, 0), (30, 20, t))
    wall = box_span("wall", (-30, -20, 0), (30, -20 + t, 30))
    holes = [cylinder_between(f"hole_{i + 1}", (x, 5, -2), (x, 5, t + 2), 5.0)
             for i, x in enumerate((-15, 15))]
    slot = box_span("wall_slot", (-10, -22, 15), (10, -17, 20))
    return dict(
        root=difference(union(base, wall), *holes, slot),
        title="Sheet-metal bracket",
        description="L bracket bent from 1.5 mm sheet (1.5 voxels at res 64): base 60 x 40 with "
                    "two 10 mm holes, wall 60 x 30 with a 20 x 5 slot.",
        features="walls of 1-2 voxels; holes and a slot through thin sheet",
        thinnest="1.5 mm sheet",
        tangent=[("base", "wall")])


THIN_PARTS = [
    ("slotted_plate", part_slotted_plate),
    ("thin_tray", part_thin_tray),
    ("pin_base", part_pin_base),
    ("sheet_bracket", part_sheet_bracket),
]


PARTS = [
    ("plate_holes", part_plate_holes),
    ("l_bracket", part_l_bracket),
    ("flange", part_flange),
    ("pipe_tee", part_pipe_tee),
    ("stepped_shaft", part_stepped_shaft),
    ("knob", part_knob),
    ("bearing_housing", part_bearing_housing),
    ("rotated_block", part_rotated_block),
    ("housing_complex", part_housing_complex),
    ("wedge_block", part_wedge_block),
    ("countersunk_plate", part_countersunk_plate),
    ("funnel", part_funnel),
]

# ----------------------------------------------------------------------------
# Validation of parameters.

EPS_UNIT = 1e-9


def check_unit(v, what):
    if len(v) != 3 or not all(math.isfinite(c) for c in v):
        raise ValueError(f"{what}: not a finite 3-vector")
    if abs(norm(v) - 1.0) > EPS_UNIT:
        raise ValueError(f"{what}: not unit (|v| = {norm(v)!r})")


def check_finite(v, what):
    if len(v) != 3 or not all(math.isfinite(c) for c in v):
        raise ValueError(f"{what}: not a finite 3-vector")


def check_positive(x, what):
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError(f"{what}: must be finite and > 0 (got {x!r})")


def validate_node(node, path="root"):
    if "op" in node:
        op = node["op"]
        if op not in ("union", "intersection", "difference", "complement"):
            raise ValueError(f"{path}: unknown op {op!r}")
        kids = node["children"]
        if not kids or (op == "complement" and len(kids) != 1):
            raise ValueError(f"{path}: bad arity for {op}")
        if op != "complement" and len(kids) < 2:
            raise ValueError(f"{path}: {op} with a single operand is pointless")
        for i, c in enumerate(kids):
            validate_node(c, f"{path}/{op}[{i}]")
        return
    t = node["type"]
    what = f"{path}/{node.get('name', '?')}"
    if not node.get("name"):
        raise ValueError(f"{what}: unnamed primitive")
    if t == "halfspace":
        check_unit(node["normal"], what + " normal")
        if not math.isfinite(node["offset"]):
            raise ValueError(what + ": offset not finite")
        return
    check_finite(node["center"], what + " center")
    if t == "box":
        a = node["axes"]
        for i in range(3):
            check_unit(a[i], f"{what} axis {i}")
            check_positive(node["half_size"][i], f"{what} half_size[{i}]")
        for i in range(3):
            for j in range(i + 1, 3):
                if abs(dot(a[i], a[j])) > EPS_UNIT:
                    raise ValueError(f"{what}: axes {i} and {j} not orthogonal")
        if dot(cross(a[0], a[1]), a[2]) < 1.0 - EPS_UNIT:
            raise ValueError(f"{what}: axes not right-handed")
    elif t == "cylinder":
        check_unit(node["axis"], what + " axis")
        check_positive(node["radius"], what + " radius")
        check_positive(node["height"], what + " height")
    elif t == "cone":
        check_unit(node["axis"], what + " axis")
        check_positive(node["height"], what + " height")
        rb, rt = node["radius_bottom"], node["radius_top"]
        if not (math.isfinite(rb) and math.isfinite(rt) and rb >= 0 and rt >= 0 and rb + rt > 0):
            raise ValueError(what + ": cone radii must be >= 0 and not both 0")
    elif t == "sphere":
        check_positive(node["radius"], what + " radius")
    elif t == "torus":
        check_unit(node["axis"], what + " axis")
        check_positive(node["major_radius"], what + " major_radius")
        check_positive(node["minor_radius"], what + " minor_radius")
        if node["minor_radius"] > node["major_radius"]:
            raise ValueError(what + ": minor_radius > major_radius")
    else:
        raise ValueError(f"{what}: unknown primitive type {t!r}")


def directions(node):
    if node["type"] == "box":
        return list(node["axes"])
    if node["type"] == "halfspace":
        return [node["normal"]]
    if node["type"] in ("cylinder", "cone", "torus"):
        return [node["axis"]]
    return []


def check_off_axis(root, min_degrees=5.0):
    """Raises when a direction of any primitive is within min_degrees of a world axis.
    Returns the smallest angle found (degrees)."""
    worst = 90.0
    for leaf in leaves(root):
        for d in directions(leaf):
            angle = math.degrees(math.acos(min(1.0, max(abs(c) for c in d))))
            worst = min(worst, angle)
            if angle < min_degrees:
                raise ValueError(f"{leaf['name']}: direction {d} only {angle:.2f} deg "
                                 "off a world axis")
    return worst

# ----------------------------------------------------------------------------
# Signed distances (FRep: >= 0 inside), ported from primitives/primitive.cpp.

def _box_sd2(qx, qz, hx, hz):
    dx, dz = qx - hx, qz - hz
    if dx > 0.0 and dz > 0.0:
        return math.hypot(dx, dz)
    return max(dx, dz)


def _convex_sd2(x, y, segs):
    outside = False
    best_in = -math.inf
    best_out = math.inf
    for ax, ay, bx, by in segs:
        ex, ey = bx - ax, by - ay
        ln = math.hypot(ex, ey)
        if ln <= 0.0:
            continue
        nx, ny = ey / ln, -ex / ln
        line = (x - ax) * nx + (y - ay) * ny
        if line > 0.0:
            outside = True
        best_in = max(best_in, line)
        t = min(1.0, max(0.0, ((x - ax) * ex + (y - ay) * ey) / (ln * ln)))
        best_out = min(best_out, math.hypot(x - (ax + t * ex), y - (ay + t * ey)))
    return best_out if outside else best_in


def make_field(leaf):
    """Returns f(p) for a leaf: signed distance, >= 0 inside."""
    t = leaf["type"]
    if t == "halfspace":
        (nx, ny, nz), off = leaf["normal"], leaf["offset"]
        return lambda p: off - (nx * p[0] + ny * p[1] + nz * p[2])
    if t == "sphere":
        (cx, cy, cz), r = leaf["center"], leaf["radius"]
        return lambda p: r - math.sqrt((p[0] - cx) ** 2 + (p[1] - cy) ** 2 + (p[2] - cz) ** 2)
    if t == "box":
        (cx, cy, cz) = leaf["center"]
        (a0, a1, a2) = leaf["axes"]
        (hx, hy, hz) = leaf["half_size"]

        def f_box(p):
            dx, dy, dz = p[0] - cx, p[1] - cy, p[2] - cz
            qx = abs(a0[0] * dx + a0[1] * dy + a0[2] * dz) - hx
            qy = abs(a1[0] * dx + a1[1] * dy + a1[2] * dz) - hy
            qz = abs(a2[0] * dx + a2[1] * dy + a2[2] * dz) - hz
            m = max(qx, qy, qz)
            if m > 0.0:
                return -math.sqrt(max(qx, 0.0) ** 2 + max(qy, 0.0) ** 2 + max(qz, 0.0) ** 2)
            return -m
        return f_box
    (cx, cy, cz) = leaf["center"]
    (ux, uy, uz) = leaf["axis"]

    def meridian(p):
        dx, dy, dz = p[0] - cx, p[1] - cy, p[2] - cz
        z = ux * dx + uy * dy + uz * dz
        rho = math.sqrt(max(0.0, dx * dx + dy * dy + dz * dz - z * z))
        return rho, z
    if t == "cylinder":
        r, h = leaf["radius"], 0.5 * leaf["height"]

        def f_cyl(p):
            rho, z = meridian(p)
            return -_box_sd2(rho, abs(z), r, h)
        return f_cyl
    if t == "cone":
        h = 0.5 * leaf["height"]
        rb, rt = leaf["radius_bottom"], leaf["radius_top"]
        segs = ((0.0, -h, rb, -h), (rb, -h, rt, h), (rt, h, 0.0, h))

        def f_cone(p):
            rho, z = meridian(p)
            return -_convex_sd2(rho, z, segs)
        return f_cone
    if t == "torus":
        R, r = leaf["major_radius"], leaf["minor_radius"]

        def f_torus(p):
            rho, z = meridian(p)
            return r - math.hypot(rho - R, z)
        return f_torus
    raise ValueError(t)


def leaf_bounds(leaf):
    """Axis-aligned bounds (lo, hi) of a leaf; None for a half-space."""
    t = leaf["type"]
    if t == "halfspace":
        return None
    c = leaf["center"]
    if t == "sphere":
        r = leaf["radius"]
        return (sub(c, (r, r, r)), add(c, (r, r, r)))
    if t == "box":
        e = tuple(sum(abs(leaf["axes"][j][i]) * leaf["half_size"][j] for j in range(3))
                  for i in range(3))
        return (sub(c, e), add(c, e))
    a = leaf["axis"]

    def disc(r):
        return tuple(r * math.sqrt(max(0.0, 1.0 - a[k] * a[k])) for k in range(3))
    if t == "cylinder":
        h = 0.5 * leaf["height"]
        e = add(disc(leaf["radius"]), tuple(h * abs(x) for x in a))
        return (sub(c, e), add(c, e))
    if t == "cone":
        h = 0.5 * leaf["height"]
        bot, top = sub(c, scale(a, h)), add(c, scale(a, h))
        eb, et = disc(leaf["radius_bottom"]), disc(leaf["radius_top"])
        pts = [sub(bot, eb), add(bot, eb), sub(top, et), add(top, et)]
        return (tuple(min(p[i] for p in pts) for i in range(3)),
                tuple(max(p[i] for p in pts) for i in range(3)))
    if t == "torus":
        r = leaf["minor_radius"]
        e = add(disc(leaf["major_radius"] + r), tuple(r * abs(x) for x in a))
        return (sub(c, e), add(c, e))
    raise ValueError(t)


def tree_bounds(node):
    """Conservative bounds as CsgTree::bounds computes them; None = unbounded."""
    if "op" not in node:
        return leaf_bounds(node)
    op = node["op"]
    if op == "complement":
        return None
    if op == "difference":
        return tree_bounds(node["children"][0])
    bs = [tree_bounds(c) for c in node["children"]]
    if op == "union":
        if any(b is None for b in bs):
            return None
        return (tuple(min(b[0][i] for b in bs) for i in range(3)),
                tuple(max(b[1][i] for b in bs) for i in range(3)))
    bs = [b for b in bs if b is not None]
    if not bs:
        return None
    return (tuple(max(b[0][i] for b in bs) for i in range(3)),
            tuple(min(b[1][i] for b in bs) for i in range(3)))


def tree_value(node, p):
    """FRep value of the tree with min/max operations (>= 0 inside)."""
    if "op" not in node:
        return make_field(node)(p)
    vals = [tree_value(c, p) for c in node["children"]]
    op = node["op"]
    if op == "union":
        return max(vals)
    if op == "intersection":
        return min(vals)
    if op == "difference":
        return min([vals[0]] + [-v for v in vals[1:]])
    return -vals[0]

# ----------------------------------------------------------------------------
# Point sets as bitsets (Python ints) and the classification of trees.

def classify_leaf(leaf, points):
    f = make_field(leaf)
    bits = bytearray((len(points) + 7) // 8)
    for i, p in enumerate(points):
        if f(p) >= 0.0:
            bits[i >> 3] |= 1 << (i & 7)
    return int.from_bytes(bits, "little")


def evaluate_bits(node, leaf_bits, full, removed=None):
    """Bitset of the points inside the tree. leaf_bits maps id(leaf) -> bits.
    `removed` is a leaf treated as absent: the empty set in a union, a
    complement or a difference's first operand; skipped in an intersection or
    as a later difference operand."""
    if "op" not in node:
        return leaf_bits[id(node)]
    op = node["op"]
    kids = node["children"]
    if op == "union":
        acc = 0
        for c in kids:
            if c is not removed:
                acc |= evaluate_bits(c, leaf_bits, full, removed)
        return acc
    if op == "intersection":
        acc = full
        for c in kids:
            if c is not removed:
                acc &= evaluate_bits(c, leaf_bits, full, removed)
        return acc
    if op == "difference":
        if kids[0] is removed:
            return 0
        acc = evaluate_bits(kids[0], leaf_bits, full, removed)
        for c in kids[1:]:
            if c is not removed:
                acc &= ~evaluate_bits(c, leaf_bits, full, removed)
        return acc & full
    inner = 0 if kids[0] is removed else evaluate_bits(kids[0], leaf_bits, full, removed)
    return full & ~inner


def stratified_points(lo, hi, count, rng):
    """About `count` points, one uniform point in each cell of a grid over the box."""
    size = sub(hi, lo)
    vol = size[0] * size[1] * size[2]
    s = (count / vol) ** (1.0 / 3.0)
    n = [max(1, round(size[i] * s)) for i in range(3)]
    pts = []
    for k in range(n[2]):
        for j in range(n[1]):
            for i in range(n[0]):
                pts.append((lo[0] + (i + rng.random()) * size[0] / n[0],
                            lo[1] + (j + rng.random()) * size[1] / n[1],
                            lo[2] + (k + rng.random()) * size[2] / n[2]))
    return pts


def grid_points(lo, hi, res):
    """Voxel centres of a grid with `res` cells along the longest side, padded
    with one empty layer on every side. Returns (points, dims, cell, real)."""
    size = sub(hi, lo)
    cell = max(size) / res
    n = [max(1, math.ceil(size[i] / cell - 1e-9)) for i in range(3)]
    org = tuple(lo[i] + 0.5 * (size[i] - n[i] * cell) for i in range(3))
    dims = [n[i] + 2 for i in range(3)]
    pts = []
    real = 0
    bit = 0
    for k in range(dims[2]):
        for j in range(dims[1]):
            for i in range(dims[0]):
                if 0 < i <= n[0] and 0 < j <= n[1] and 0 < k <= n[2]:
                    real |= 1 << bit
                bit += 1
                pts.append((org[0] + (i - 0.5) * cell, org[1] + (j - 0.5) * cell,
                            org[2] + (k - 0.5) * cell))
    return pts, dims, cell, real


def opening_residue(mask, dims, region):
    """Bits of `mask` (within `region`) that no 2x2x2 block inside `mask` covers."""
    sx, sy = 1, dims[0]
    sz = dims[0] * dims[1]
    offs = [a + b + c for a in (0, sx) for b in (0, sy) for c in (0, sz)]
    eroded = mask
    for o in offs[1:]:
        eroded &= mask >> o
    dilated = 0
    for o in offs:
        dilated |= eroded << o
    return mask & ~dilated & region


def bits_extent(bits, points):
    lo = [math.inf] * 3
    hi = [-math.inf] * 3
    i = 0
    while bits:
        if bits & 1:
            p = points[i]
            for k in range(3):
                lo[k] = min(lo[k], p[k])
                hi[k] = max(hi[k], p[k])
        bits >>= 1
        i += 1
    return lo, hi

# ----------------------------------------------------------------------------
# Surface samples for the parallel-surface check.

def surface_samples(leaf, count, rng, box_lo, box_hi):
    """About `count` (point, outward unit normal) pairs spread over the leaf's
    surface by area. A half-space's plane is sampled inside [box_lo, box_hi]."""
    t = leaf["type"]
    out = []
    if t == "halfspace":
        n = tuple(leaf["normal"])
        tries = 0
        while len(out) < count and tries < 50 * count:
            tries += 1
            q = tuple(box_lo[i] + rng.random() * (box_hi[i] - box_lo[i]) for i in range(3))
            p = sub(q, scale(n, dot(n, q) - leaf["offset"]))
            if all(box_lo[i] <= p[i] <= box_hi[i] for i in range(3)):
                out.append((p, n))
        return out
    c = tuple(leaf["center"])
    if t == "sphere":
        r = leaf["radius"]
        for _ in range(count):
            d = unit((rng.gauss(0, 1), rng.gauss(0, 1), rng.gauss(0, 1)))
            out.append((add(c, scale(d, r)), d))
        return out
    if t == "box":
        a, h = leaf["axes"], leaf["half_size"]
        faces = []  # (axis index, sign, area)
        for k in range(3):
            area = 4.0 * h[(k + 1) % 3] * h[(k + 2) % 3]
            faces += [(k, 1.0, area), (k, -1.0, area)]
        total = sum(f[2] for f in faces)
        for _ in range(count):
            x = rng.random() * total
            for k, s, area in faces:
                if x <= area:
                    break
                x -= area
            local = [0.0, 0.0, 0.0]
            for m in range(3):
                local[m] = s * h[m] if m == k else (2.0 * rng.random() - 1.0) * h[m]
            p = c
            for m in range(3):
                p = add(p, scale(a[m], local[m]))
            out.append((p, scale(a[k], s)))
        return out
    ax = tuple(leaf["axis"])
    u, v = perpendicular_frame(ax)

    def at(rho, phi, z):
        radial = add(scale(u, math.cos(phi)), scale(v, math.sin(phi)))
        return add(add(c, scale(radial, rho)), scale(ax, z)), radial

    if t == "torus":
        R, r = leaf["major_radius"], leaf["minor_radius"]
        while len(out) < count:
            th = rng.random() * 2.0 * math.pi
            if rng.random() * (R + r) > R + r * math.cos(th):
                continue
            phi = rng.random() * 2.0 * math.pi
            _, radial = at(1.0, phi, 0.0)
            nrm = add(scale(radial, math.cos(th)), scale(ax, math.sin(th)))
            p, _ = at(R + r * math.cos(th), phi, r * math.sin(th))
            out.append((p, nrm))
        return out
    h = 0.5 * leaf["height"]
    if t == "cylinder":
        rb = rt = leaf["radius"]
    else:
        rb, rt = leaf["radius_bottom"], leaf["radius_top"]
    slant = math.hypot(rt - rb, 2.0 * h)
    a_side = math.pi * (rb + rt) * slant
    a_bot, a_top = math.pi * rb * rb, math.pi * rt * rt
    total = a_side + a_bot + a_top
    # Outward normal of the lateral surface in (radial, axial) components.
    side_n = unit((2.0 * h, 0.0, rb - rt))
    for _ in range(count):
        x = rng.random() * total
        phi = rng.random() * 2.0 * math.pi
        if x < a_side:
            # Radius linear in s; density proportional to the radius.
            w = rng.random()
            if abs(rt - rb) < 1e-12:
                s = w
            else:
                rr = math.sqrt(rb * rb + w * (rt * rt - rb * rb))
                s = (rr - rb) / (rt - rb)
            rho = rb + s * (rt - rb)
            p, radial = at(rho, phi, -h + 2.0 * h * s)
            nrm = add(scale(radial, side_n[0]), scale(ax, side_n[2]))
        elif x < a_side + a_bot:
            p, _ = at(rb * math.sqrt(rng.random()), phi, -h)
            nrm = scale(ax, -1.0)
        else:
            p, _ = at(rt * math.sqrt(rng.random()), phi, h)
            nrm = ax
        out.append((p, nrm))
    return out


def field_gradient(f, p, step=1e-4):
    g = []
    for k in range(3):
        e = [0.0, 0.0, 0.0]
        e[k] = step
        g.append((f(add(p, e)) - f(sub(p, e))) / (2.0 * step))
    n = norm(g)
    return tuple(x / n for x in g) if n > 0 else (0.0, 0.0, 0.0)


def parallel_surface_pairs(leaf_list, tangent, rng, box_lo, box_hi, samples=2000,
                           gap=1.0, cos_tol=0.999, max_share=0.0):
    """Pairs of leaves (a, b, share) where more than max_share of a's surface
    samples lie within `gap` of b's surface with parallel normals (within
    2.6 degrees). Surfaces that cross at an angle never count, so by default
    a single such sample is an error."""
    allowed = {frozenset(p) for p in tangent}
    fields = [make_field(l) for l in leaf_list]
    bad = []
    for ia, la in enumerate(leaf_list):
        pts = surface_samples(la, samples, rng, box_lo, box_hi)
        if not pts:
            continue
        for ib, lb in enumerate(leaf_list):
            if ia == ib or frozenset((la["name"], lb["name"])) in allowed:
                continue
            fb = fields[ib]
            hits = 0
            for p, n in pts:
                v = fb(p)
                if abs(v) < gap and abs(dot(n, field_gradient(fb, p))) > cos_tol:
                    hits += 1
            share = hits / len(pts)
            if share > max_share:
                bad.append((la["name"], lb["name"], share))
    return bad

# ----------------------------------------------------------------------------
# Analysis of one part.

MC_SKIN = 2.0  # mm added around the solid's box for the Monte-Carlo check


def analyse(name, part, n_points, res=64):
    root = part["root"]
    validate_node(root)
    leaf_list = list(leaves(root))
    names = [l["name"] for l in leaf_list]
    if len(set(names)) != len(names):
        raise ValueError(f"{name}: duplicate leaf names")
    worst_axis_angle = check_off_axis(root) if part.get("off_axis") else None
    rng = random.Random(zlib.crc32(name.encode()))

    cons = tree_bounds(root)
    if cons is None or not all(math.isfinite(x) for x in cons[0] + cons[1]):
        raise ValueError(f"{name}: unbounded solid")
    # A voxel grid over the conservative bounds gives the solid's real extent.
    pts, dims, cell, real = grid_points(cons[0], cons[1], res)
    full = (1 << len(pts)) - 1
    bits = {id(l): classify_leaf(l, pts) for l in leaf_list}
    inside = evaluate_bits(root, bits, full)
    if not inside:
        raise ValueError(f"{name}: the solid is empty")
    glo, ghi = bits_extent(inside, pts)
    lo = tuple(max(cons[0][i], glo[i] - cell) for i in range(3))
    hi = tuple(min(cons[1][i], ghi[i] + cell) for i in range(3))
    if any(hi[i] - lo[i] < cons[1][i] - cons[0][i] - 2.0 * cell for i in range(3)):
        # The conservative bounds were loose: redo the grid on the solid's box.
        pts, dims, cell, real = grid_points(lo, hi, res)
        full = (1 << len(pts)) - 1
        bits = {id(l): classify_leaf(l, pts) for l in leaf_list}
        inside = evaluate_bits(root, bits, full)
    n_solid = (inside & real).bit_count()
    thin_solid = opening_residue(inside, dims, real).bit_count()
    empty = full & ~inside
    n_empty = (empty & real).bit_count()
    thin_empty = opening_residue(empty, dims, real).bit_count()

    # Monte-Carlo leaf effects on stratified random points in the solid's box
    # grown by a skin of MC_SKIN mm: a leaf that only bounds the solid (the
    # block of an intersection) changes nothing inside the solid's own box.
    mlo = tuple(x - MC_SKIN for x in lo)
    mhi = tuple(x + MC_SKIN for x in hi)
    mc = stratified_points(mlo, mhi, n_points, rng)
    full = (1 << len(mc)) - 1
    bits = {id(l): classify_leaf(l, mc) for l in leaf_list}
    inside = evaluate_bits(root, bits, full)
    frac = inside.bit_count() / len(mc)
    msize = sub(mhi, mlo)
    volume = frac * msize[0] * msize[1] * msize[2]
    size = sub(hi, lo)
    effects = []
    for l in leaf_list:
        changed = (evaluate_bits(root, bits, full, removed=l) ^ inside).bit_count()
        effects.append((l["name"], changed / len(mc)))
    weak = [(n, e) for n, e in effects if e < 0.001]

    pad = 2.0
    parallel = parallel_surface_pairs(leaf_list, part.get("tangent", []), rng,
                                      tuple(x - pad for x in lo), tuple(x + pad for x in hi))
    types = sorted({l["type"] for l in leaf_list})
    return dict(
        name=name, prims=len(leaf_list), ops=operation_count(root), depth=depth(root),
        size=size, lo=lo, hi=hi, volume=volume, n_mc=len(mc), effects=effects, weak=weak,
        min_effect=min(effects, key=lambda e: e[1]), parallel=parallel, types=types,
        thin_solid=thin_solid / max(1, n_solid), thin_empty=thin_empty / max(1, n_empty),
        cell=cell, worst_axis_angle=worst_axis_angle,
        diag=math.sqrt(sum(s * s for s in size)))

# ----------------------------------------------------------------------------
# Output.

README_HEAD = """\
# Ground-truth parts

CSG trees of real mechanical parts, used as ground truth for csgvox: sample or
voxelize a tree, reconstruct it, compare with the original. Each folder holds
one `tree.json` in csgvox's format (`{"format": "csgvox-tree", "version": 1,
"root": ...}`, see `io/tree_json.cpp`). Units are millimetres.

Everything here is generated: edit `make_parts.py` and run

    python3 data/make_parts.py

which rewrites every `data/<part>/tree.json` and this README (standard
library only, deterministic). `data/make_scans.sh` then writes each part's
scans with `csgvox sample`: `scan.ply` (clean) and `scan_noisy.ply` (Gaussian
noise, σ = 0.5 % of the diagonal), 10 000 points with normals, and
`scan_scanner.ply`, 20 000 raw x y z points from the turntable scanner model
at its defaults ([docs/scanner.md](../docs/scanner.md)).

## Design rules

* Whole parts 20-150 mm; every primitive has a name (`base`, `hole_1`, ...).
* No feature thinner than about 3 % of the part's bounding-box diagonal
  (walls, ribs, ligaments between holes and edges, groove and slot widths), so
  a voxelization at resolution 64 still sees it.
* No coincident faces: union operands overlap by at least 1 mm, and tools that
  are subtracted stick out at least 1 mm (mostly 2 mm) past every face they
  cut. The only surfaces that touch are tangencies a designer would draw on
  purpose: a fillet torus touching the plate and the boss it blends, and the
  flanks of an obround slot's box touching its end cylinders.
* No redundant primitives: each leaf changes the solid, so the primitive count
  is the designed count.
* n-ary operations where they are natural, e.g.
  `difference(union(base, boss, ...), bore, hole_1, hole_2, ...)`.
* Concave fillets are modelled as `difference(ring_cylinder, torus)`,
  chamfers as intersection with a cone or half-space (or subtraction of
  a half-space), counterbores and countersinks as extra coaxial tools.
* `complement` is not used: no part needed it.

## Checks done by the script

* Parameters: unit axes and normals, right-handed orthonormal box frames,
  positive sizes, cone radii >= 0 (not both 0), torus minor <= major, unique
  leaf names, no one-operand union/intersection/difference.
* Off-axis parts (pipe_tee, knob, rotated_block): every box axis,
  cylinder/cone/torus axis and half-space normal is at least 5 degrees from
  every world axis.
* Every leaf matters: on about 20000 stratified random points in the solid's
  bounding box grown by 2 mm on every side (without that skin, the block of
  an intersection that only bounds the solid would change nothing),
  removing the leaf (empty set in a union, a complement or a difference's
  first operand; skipped in an intersection or as a later difference
  operand) changes at least 0.1 % of the points' classification.
  The table gives the smallest such change per part.
* Parallel surfaces: surface samples of each primitive are tested against
  every other primitive; a patch lying within 1 mm of another primitive's
  surface with a parallel normal counts as coincident, or as an overlap or
  clearance under 1 mm. Only the tangencies listed above are exempt.
* Thinness (reported, not enforced): on a voxel grid with 64 cells along the
  longest side, the share of solid voxels (and of empty voxels) that no 2x2x2
  block of solid (empty) voxels covers. Values under a few per cent come from
  sharp edges, for example acute wedges, chamfers and where a round hole meets
  a face.
"""


def fmt_size(s):
    return " x ".join(f"{x:.1f}" for x in s)


def write_readme(path, parts, results):
    lines = [README_HEAD, "## Parts", ""]
    lines.append("| part | primitives | ops | depth | bounding box (mm) | volume (cm^3) | "
                 "types | smallest leaf effect |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for (name, part), r in zip(parts, results):
        lines.append(f"| [{name}]({name}/tree.json) | {r['prims']} | {r['ops']} | "
                     f"{r['depth']} | {fmt_size(r['size'])} | {r['volume'] / 1000:.1f} | "
                     f"{', '.join(r['types'])} | "
                     f"{r['min_effect'][0]} {100 * r['min_effect'][1]:.2f} % |")
    lines.append("")
    lines.append("Bounding boxes and volumes are estimates from the sampled solid (the boxes "
                 "of rotated parts are taken from a 64-cell grid and may be up to one cell "
                 "large). Depth counts a single leaf as 1.")
    lines.append("")
    for (name, part), r in zip(parts, results):
        lines.append(f"### {name}: {part['title']}")
        lines.append("")
        lines.append(part["description"])
        lines.append("")
        ops = f"{r['ops']} operation" + ("s" if r["ops"] != 1 else "")
        lines.append(f"* {r['prims']} primitives ({', '.join(r['types'])}), {ops}, "
                     f"depth {r['depth']}.")
        lines.append(f"* Exercises: {part['features']}.")
        lines.append(f"* Thinnest feature: {part['thinnest']}; 3 % of the bounding-box "
                     f"diagonal is {0.03 * r['diag']:.1f} mm.")
        leaves_txt = ", ".join(f"`{l['name']}`" for l in leaves(part["root"]))
        lines.append(f"* Leaves: {leaves_txt}.")
        if part.get("tangent"):
            pairs = ", ".join(f"`{a}`/`{b}`" for a, b in part["tangent"])
            lines.append(f"* Tangent by design: {pairs}.")
        lines.append("")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines).rstrip("\n") + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)),
                    help="output folder (default: the folder of this script)")
    ap.add_argument("--points", type=int, default=20000, help="Monte-Carlo points per part")
    ap.add_argument("--no-readme", action="store_true", help="do not rewrite README.md")
    ap.add_argument("--only", nargs="*", help="only these parts")
    ap.add_argument("--thin", action="store_true",
                    help="the thin-feature parts instead, into <out>/thin/ (no README)")
    args = ap.parse_args(argv)

    catalogue = THIN_PARTS if args.thin else PARTS
    if args.thin:
        args.out = os.path.join(args.out, "thin")
        args.no_readme = True
    parts = [(n, fn()) for n, fn in catalogue if not args.only or n in args.only]
    results = []
    failures = []
    header = (f"{'part':<18} {'prims':>5} {'ops':>3} {'depth':>5}  {'bounding box (mm)':<22} "
              f"{'volume cm3':>10}  {'min effect':>22}  {'thin s/e %':>10}")
    print(header)
    print("-" * len(header))
    for name, part in parts:
        r = analyse(name, part, args.points)
        results.append(r)
        me = r["min_effect"]
        print(f"{name:<18} {r['prims']:>5} {r['ops']:>3} {r['depth']:>5}  "
              f"{fmt_size(r['size']):<22} "
              f"{r['volume'] / 1000:>10.2f}  {me[0]:>14} {100 * me[1]:5.2f} %  "
              f"{100 * r['thin_solid']:4.1f}/{100 * r['thin_empty']:3.1f}")
        for n, e in r["weak"]:
            failures.append(f"{name}: leaf {n} changes only {100 * e:.3f} % of the points")
        for a, b, s in r["parallel"]:
            failures.append(f"{name}: {100 * s:.1f} % of {a}'s surface lies within 1 mm of "
                            f"{b}'s surface and parallel to it")
        doc = {"format": "csgvox-tree", "version": 1, "root": part["root"]}
        folder = os.path.join(args.out, name)
        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(folder, "tree.json"), "w", encoding="utf-8") as f:
            json.dump(doc, f, indent=2)
            f.write("\n")

    types_in = {}
    for (name, _), r in zip(parts, results):
        for t in r["types"]:
            types_in.setdefault(t, []).append(name)
    if not args.only and not args.thin:
        for t in ("box", "cylinder", "cone", "sphere", "torus", "halfspace"):
            if len(types_in.get(t, [])) < 2:
                failures.append(f"primitive type {t} appears in fewer than two parts")
        print()
        for t in sorted(types_in):
            print(f"{t:<9} in {len(types_in[t]):>2} parts: {', '.join(types_in[t])}")
    off = [(n, r["worst_axis_angle"]) for (n, _), r in zip(parts, results)
           if r["worst_axis_angle"] is not None]
    if off:
        print("off-axis parts (smallest angle to a world axis): " +
              ", ".join(f"{n} {a:.1f} deg" for n, a in off))
    if not args.no_readme and not args.only:
        write_readme(os.path.join(args.out, "README.md"), parts, results)
    if failures:
        print("\nFAILED CHECKS:", file=sys.stderr)
        for f in failures:
            print("  " + f, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
