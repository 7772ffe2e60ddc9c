#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets into fuzz/corpus/<target>/.

Point clouds are the first points of bundled scans (data/*/scan.ply), in
every encoding the readers take; meshes are a few small solids in each mesh
format; trees are the bundled data/*/tree.json. The PLY seeds start after
the "ply" and format lines, as the PLY targets add those themselves.
Usage: fuzz/make_corpus.py (from anywhere; about 200 kB are written).
"""
import json
import pathlib
import struct

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "fuzz" / "corpus"
POINTS = 60  # points per seed cloud


def read_scan(path, count):
    """First `count` rows (x y z nx ny nz) of a binary little-endian PLY."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    props = [line.split()[-1] for line in header.splitlines() if line.startswith("property")]
    assert "binary_little_endian" in header and props[:6] == ["x", "y", "z", "nx", "ny", "nz"], path
    row = 4 * len(props)
    return [struct.unpack_from("<6f", data, end + i * row) for i in range(count)]


def ply_body(rows, normals, data, faces=None, extra=""):
    """A PLY without its first two lines; `data` is "ascii", "<" or ">"."""
    props = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals else [])
    ftype = "double" if extra == "double" else "float"
    text = f"comment seed\nelement vertex {len(rows)}\n"
    text += "".join(f"property {ftype} {p}\n" for p in props)
    if faces is not None:
        text += f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
    text += "end_header\n"
    body = text.encode()
    n = len(props)
    for r in rows:
        if data == "ascii":
            body += (" ".join(f"{v:.6g}" for v in r[:n]) + "\n").encode()
        else:
            body += struct.pack(data + ("d" if ftype == "double" else "f") * n, *r[:n])
    for f in faces or []:
        if data == "ascii":
            body += (" ".join(str(v) for v in [len(f)] + list(f)) + "\n").encode()
        else:
            body += struct.pack(data + "B" + "i" * len(f), len(f), *f)
    return body


# A cube (quads, outward) and a tetrahedron (triangles).
CUBE_V = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
CUBE_F = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
TET_V = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def triangles(faces):
    return [(f[0], f[i], f[i + 1]) for f in faces for i in range(1, len(f) - 1)]


def off(v, f):
    return f"OFF\n{len(v)} {len(f)} 0\n" + "".join(f"{a} {b} {c}\n" for a, b, c in v) + \
        "".join(" ".join(map(str, (len(x),) + tuple(x))) + "\n" for x in f)


def obj(v, f):
    return "# seed\n" + "".join(f"v {a} {b} {c}\n" for a, b, c in v) + \
        "".join("f " + " ".join(str(i + 1) for i in x) + "\n" for x in f)


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    w = [c[i] - a[i] for i in range(3)]
    return (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])


def stl_ascii(v, f):
    text = "solid seed\n"
    for t in triangles(f):
        p = [v[i] for i in t]
        text += " facet normal %g %g %g\n  outer loop\n" % normal(*p)
        text += "".join("   vertex %g %g %g\n" % q for q in p)
        text += "  endloop\n endfacet\n"
    return text + "endsolid seed\n"


def stl_binary(v, f):
    tris = triangles(f)
    body = b"binary seed".ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        p = [v[i] for i in t]
        body += struct.pack("<12fH", *normal(*p), *p[0], *p[1], *p[2], 0)
    return body


def write(target, name, content):
    folder = OUT / target
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(content.encode() if isinstance(content, str) else content)


def main():
    scans = sorted((ROOT / "data").glob("*/scan.ply"))[:3]
    for scan in scans:
        part = scan.parent.name
        rows = read_scan(scan, POINTS)
        write("ply_ascii", f"{part}-normals", ply_body(rows, True, "ascii"))
        write("ply_ascii", f"{part}-points", ply_body(rows, False, "ascii"))
        write("ply_binary", f"{part}-le-normals", b"\0" + ply_body(rows, True, "<"))
        write("ply_binary", f"{part}-be-points", b"\1" + ply_body(rows, False, ">"))
        write("xyz", f"{part}.xyzn", "".join(" ".join(f"{v:.6g}" for v in r) + "\n" for r in rows))
        write("xyz", f"{part}.xyz", f"{len(rows)}\n" + "".join(
            " ".join(f"{v:.6g}" for v in r[:3]) + "\n" for r in rows))
    rows = read_scan(scans[0], 10)
    write("ply_binary", "double-le", b"\0" + ply_body(rows, True, "<", extra="double"))
    for name, v, f in (("cube", CUBE_V, CUBE_F), ("tet", TET_V, TET_F)):
        write("ply_ascii", f"{name}-mesh", ply_body(v, False, "ascii", f))
        write("ply_binary", f"{name}-mesh-le", b"\0" + ply_body(v, False, "<", f))
        write("ply_binary", f"{name}-mesh-be", b"\1" + ply_body(v, False, ">", f))
        write("off", f"{name}.off", off(v, f))
        write("obj", f"{name}.obj", obj(v, f))
        write("stl", f"{name}-ascii.stl", stl_ascii(v, f))
        write("stl", f"{name}-binary.stl", stl_binary(v, f))
    write("off", "cube-colours.off", f"COFF\n# coloured\n{len(CUBE_V)} {len(CUBE_F)} 0\n" +
          "".join(f"{a} {b} {c} 255 0 0 255\n" for a, b, c in CUBE_V) +
          "".join(" ".join(map(str, (len(x),) + x)) + " 0 0 255\n" for x in CUBE_F))
    write("obj", "cube-slashes.obj", "".join(f"v {a} {b} {c}\n" for a, b, c in CUBE_V) +
          "vn 0 0 1\nvt 0 0\n" + "".join(
              "f " + " ".join(f"{i + 1}/1/1" for i in x) + "\n" for x in CUBE_F))
    for tree in sorted((ROOT / "data").glob("*/tree.json")):
        json.loads(tree.read_text())  # each seed is valid
        write("tree_json", tree.parent.name + ".json", tree.read_bytes())


if __name__ == "__main__":
    main()
