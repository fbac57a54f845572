#!/usr/bin/env python3
"""Writes shimmer's mesh content: the assets and scene files of the mesh
shots (docs/scenes.md, "Mesh shots"), from nothing but this script, so the
project carries no third-party file.

    python3 scripts/generate-assets.py [OUT_DIR]     (default: experiments/scenes)
    python3 scripts/generate-assets.py --bench DIR   the speed report's 100k-triangle torus
                                                     (torus-100k.glb and its scene torus-100k.json)

Every byte is a function of this script: the same run writes the same files,
and a test (tests/renderer/generated_assets_test) regenerates them and
compares with the committed ones. Between them the files use every loader
feature a real asset brings: external and data-URI buffers, a GLB, a node
hierarchy with transforms, normals given and tangents left out (shimmer
computes them, with a warning), PNG textures (normal and metallic-roughness),
and OBJ with its MTL.

The shots:
  torus-lowpoly  a torus of 12 x 6 quads, smooth-shaded: its vertex normals
                 are the torus's exact ones, interpolated across flat
                 triangles, so the shading normal turns fast where the
                 geometry does not (Tokuyoshi and Kaplanyan 2019's case)
  torus-fine     the same torus at 192 x 96 quads: interpolated curvature
                 close to the true one, against which the low-poly one is seen
  panel          a gently curved panel with a normal texture (scale 0.8) and
                 a metallic-roughness texture (roughness in G, glTF 2.0)
  cable          a thin sagging cable (radius 0.012 over a 4-unit span), OBJ
                 and MTL
  tk19-fig1      Tokuyoshi and Kaplanyan 2019's Fig. 1 situation: a large
                 ground plane under a low light seen near the horizon, with
                 low-poly smooth-shaded spheres and a low-poly torus on it
"""
import base64
import json
import math
import os
import struct
import sys
import zlib

# --- geometry -----------------------------------------------------------------


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def torus(major, minor, around, tube):
    """A torus about +y: `around` quads along the ring, `tube` around the tube.
    Returns positions, exact normals, uv and counter-clockwise indices."""
    pos, nrm, uv, idx = [], [], [], []
    for i in range(around + 1):
        u = i / around
        phi = 2 * math.pi * u
        for j in range(tube + 1):
            v = j / tube
            theta = 2 * math.pi * v
            n = (math.cos(theta) * math.cos(phi), math.sin(theta), math.cos(theta) * math.sin(phi))
            c = (major * math.cos(phi), 0.0, major * math.sin(phi))
            pos.append(tuple(c[k] + minor * n[k] for k in range(3)))
            nrm.append(n)
            uv.append((u * 4, v))
    row = tube + 1
    for i in range(around):
        for j in range(tube):
            a, b = i * row + j, (i + 1) * row + j
            idx += [a, a + 1, b, b, a + 1, b + 1]
    return pos, nrm, uv, idx


def icosphere(levels):
    """The icosahedron split `levels` times, on the unit sphere (the same
    construction as the renderer tests' generated_meshes.h)."""
    t = (1 + math.sqrt(5)) / 2
    pos = [normalize(p) for p in [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
                                  (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    idx = [0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
           3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1]
    for _ in range(levels):
        middle = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                pos.append(normalize(tuple(pos[a][k] + pos[b][k] for k in range(3))))
                middle[key] = len(pos) - 1
            return middle[key]

        nxt = []
        for k in range(0, len(idx), 3):
            a, b, c = idx[k:k + 3]
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nxt += [a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca]
        idx = nxt
    return pos, list(pos), idx


def panel(width, height, bend, nu, nv):
    """A panel bent about +y (a cylinder section of sagitta `bend`), facing +z;
    uv over [0, 2] x [0, 2] (v down the texture, as glTF)."""
    radius = (width * width / 4 + bend * bend) / (2 * bend)
    half = math.asin(width / 2 / radius)
    pos, nrm, uv, idx = [], [], [], []
    for j in range(nv + 1):
        v = j / nv
        for i in range(nu + 1):
            u = i / nu
            a = -half + 2 * half * u
            pos.append((radius * math.sin(a), height * (0.5 - v), radius * math.cos(a) - radius))
            nrm.append((math.sin(a), 0.0, math.cos(a)))
            uv.append((2 * u, 2 * v))
    row = nu + 1
    for j in range(nv):
        for i in range(nu):
            a, b = j * row + i, (j + 1) * row + i
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, nrm, uv, idx


def cable(span, sag, radius, segments, sides):
    """A tube of `radius` along a catenary-like sag between (-span/2, 1, 0) and
    (span/2, 1, 0); uv: u along the cable (one unit per scene unit), v around."""
    centre, tangent = [], []
    for i in range(segments + 1):
        s = -span / 2 + span * i / segments
        x = 2 * s / span
        centre.append((s, 1 - sag * (1 - x * x), 0.0))
        tangent.append(normalize((1.0, sag * 4 * s / (span * span) * 2, 0.0)))
    pos, nrm, uv, idx = [], [], [], []
    for i in range(segments + 1):
        t = tangent[i]
        side = (0.0, 0.0, 1.0)  # the cable lies in the xy plane: z is normal to it
        up = (side[1] * t[2] - side[2] * t[1], side[2] * t[0] - side[0] * t[2], side[0] * t[1] - side[1] * t[0])
        for j in range(sides + 1):
            a = 2 * math.pi * j / sides
            n = tuple(math.cos(a) * up[k] + math.sin(a) * side[k] for k in range(3))
            pos.append(tuple(centre[i][k] + radius * n[k] for k in range(3)))
            nrm.append(n)
            uv.append((span * i / segments, j / sides))
    row = sides + 1
    for i in range(segments):
        for j in range(sides):
            a, b = i * row + j, (i + 1) * row + j
            idx += [a, a + 1, b, a + 1, b + 1, b]
    return pos, nrm, uv, idx


def quad(half):
    """The plane y = 0 over [-half, half]^2, facing +y, uv one per unit."""
    pos = [(-half, 0.0, -half), (half, 0.0, -half), (half, 0.0, half), (-half, 0.0, half)]
    nrm = [(0.0, 1.0, 0.0)] * 4
    uv = [(0.0, 0.0), (2 * half, 0.0), (2 * half, 2 * half), (0.0, 2 * half)]
    return pos, nrm, uv, [0, 2, 1, 0, 3, 2]


# --- images -------------------------------------------------------------------


def png(width, height, rows):
    """An 8-bit RGB PNG from rows of (r, g, b) bytes."""
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def bump_normals(size):
    """A tangent-space normal texture of rounded rivet-like bumps in a grid of
    8 x 8 per tile plus a fine brushed ripple: slopes up to about 0.6."""
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            u, v = (x + 0.5) / size, (y + 0.5) / size
            gx = 0.35 * math.cos(2 * math.pi * 8 * u) * math.sin(2 * math.pi * 8 * v) + 0.12 * math.cos(2 * math.pi * 40 * u)
            gy = 0.35 * math.sin(2 * math.pi * 8 * u) * math.cos(2 * math.pi * 8 * v)
            # glTF's +Y is up the image (toward -v), so a height rising with v
            # has a negative slope along +Y.
            n = normalize((-gx, gy, 1.0))
            row.append(tuple(int(round((c * 0.5 + 0.5) * 255)) for c in n))
        rows.append(row)
    return png(size, size, rows)


def roughness_stripes(size):
    """glTF metallic-roughness: roughness in G (0.1 on the panel's plain bands,
    0.35 on the worn ones), metallic in B (1: a metal), R unused."""
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            worn = 0.5 + 0.5 * math.sin(2 * math.pi * 2 * (x + 0.5) / size)
            r = 0.1 + 0.25 * worn
            row.append((0, int(round(r * 255)), 255))
        rows.append(row)
    return png(size, size, rows)


# --- glTF ---------------------------------------------------------------------


class Gltf:
    """A glTF 2.0 document under construction: one buffer, views and accessors
    appended as meshes are added."""

    def __init__(self):
        self.blob = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "shimmer scripts/generate-assets.py"},
                    "buffers": [], "bufferViews": [], "accessors": [], "meshes": [], "nodes": [],
                    "scenes": [{"nodes": []}], "scene": 0}

    def _view(self, data, target):
        while len(self.blob) % 4:
            self.blob.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data),
                                        "target": target})
        self.blob += data
        return len(self.doc["bufferViews"]) - 1

    def _floats(self, items, kind):
        flat = [float(c) for item in items for c in item]
        view = self._view(struct.pack("<%df" % len(flat), *flat), 34962)
        acc = {"bufferView": view, "componentType": 5126, "count": len(items), "type": kind}
        if kind == "VEC3":
            # POSITION needs its bounds (glTF 2.0, "Accessors"); from the floats stored.
            stored = [struct.unpack("<f", struct.pack("<f", c))[0] for c in flat]
            acc["min"] = [min(stored[k::3]) for k in range(3)]
            acc["max"] = [max(stored[k::3]) for k in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def mesh(self, name, pos, nrm, uv, idx, material=None):
        attributes = {"POSITION": self._floats(pos, "VEC3"), "NORMAL": self._floats(nrm, "VEC3")}
        if uv is not None:
            attributes["TEXCOORD_0"] = self._floats(uv, "VEC2")
        wide = max(idx) > 65535
        view = self._view(struct.pack("<%d%s" % (len(idx), "I" if wide else "H"), *idx), 34963)
        self.doc["accessors"].append({"bufferView": view, "componentType": 5125 if wide else 5123, "count": len(idx),
                                      "type": "SCALAR"})
        primitive = {"attributes": attributes, "indices": len(self.doc["accessors"]) - 1, "mode": 4}
        if material is not None:
            primitive["material"] = material
        self.doc["meshes"].append({"name": name, "primitives": [primitive]})
        return len(self.doc["meshes"]) - 1

    def node(self, name, mesh=None, children=None, root=True, **transform):
        n = {"name": name}
        if mesh is not None:
            n["mesh"] = mesh
        if children:
            n["children"] = children
        n.update(transform)
        self.doc["nodes"].append(n)
        index = len(self.doc["nodes"]) - 1
        if root:
            self.doc["scenes"][0]["nodes"].append(index)
        return index

    def material(self, m):
        self.doc.setdefault("materials", []).append(m)
        return len(self.doc["materials"]) - 1

    def _padded_blob(self):
        return bytes(self.blob) + b"\x00" * (-len(self.blob) % 4)

    def write_gltf(self, path, buffer_file=None):
        """A .gltf; the buffer in `buffer_file` beside it, or a data URI."""
        blob = self._padded_blob()
        if buffer_file:
            with open(os.path.join(os.path.dirname(path), buffer_file), "wb") as f:
                f.write(blob)
            uri = buffer_file
        else:
            uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
        self.doc["buffers"] = [{"byteLength": len(blob), "uri": uri}]
        write_text(path, json.dumps(self.doc, indent=1, sort_keys=True) + "\n")

    def write_glb(self, path):
        blob = self._padded_blob()
        self.doc["buffers"] = [{"byteLength": len(blob)}]
        text = json.dumps(self.doc, separators=(",", ":"), sort_keys=True).encode()
        text += b" " * (-len(text) % 4)
        body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(blob), 0x004E4942) + blob
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)


def write_text(path, text):
    with open(path, "w", newline="\n") as f:
        f.write(text)


def write_scene(out, name, geometry_class, body):
    scene = {"name": name, "geometry_class": geometry_class}
    scene.update(body)
    write_text(os.path.join(out, name + ".json"), json.dumps(scene, indent=2) + "\n")


def fmt(x):
    return "%.9g" % x


# --- the shots ----------------------------------------------------------------

TORUS_CAMERA = {"target": [0, 0, 0], "distance": 5.5, "elevation_deg": 35, "azimuth_deg": 0, "fov_y_deg": 30}
TORUS_LIGHT = {"type": "directional", "direction": [0.4, 0.8, 0.45], "irradiance": [1, 1, 1]}


def write_torus_shot(out, name, geometry_class, around, tube, glb):
    """The torus of major radius 1 and minor 0.4 at `around` x `tube` quads, as
    a .glb or as a .gltf with an external .bin buffer, and its scene."""
    g = Gltf()
    g.node("torus", g.mesh("torus %dx%d" % (around, tube), *torus(1.0, 0.4, around, tube)))
    asset = name + (".glb" if glb else ".gltf")
    if glb:
        g.write_glb(os.path.join(out, asset))
    else:
        g.write_gltf(os.path.join(out, asset), name + ".bin")
    write_scene(out, name, geometry_class, {"assets": [{"file": asset}], "light": TORUS_LIGHT, "material": "ggx:0.05",
                                            "camera": TORUS_CAMERA})


def write_panel(out):
    with open(os.path.join(out, "panel-normal.png"), "wb") as f:
        f.write(bump_normals(256))
    with open(os.path.join(out, "panel-roughness.png"), "wb") as f:
        f.write(roughness_stripes(256))
    g = Gltf()
    g.doc["images"] = [{"uri": "panel-normal.png"}, {"uri": "panel-roughness.png"}]
    g.doc["samplers"] = [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}]
    g.doc["textures"] = [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}]
    m = g.material({"name": "worn metal panel", "normalTexture": {"index": 0, "scale": 0.8},
                    "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.92, 1], "metallicFactor": 1,
                                             "roughnessFactor": 1, "metallicRoughnessTexture": {"index": 1}}})
    g.node("panel", g.mesh("panel", *panel(2.4, 1.6, 0.25, 48, 32), material=m))
    g.write_gltf(os.path.join(out, "panel.gltf"))
    write_scene(out, "panel", "normal-mapped mesh", {
        # No material and no normal_map: the panel's own glTF material gives both.
        "assets": [{"file": "panel.gltf"}],
                               "light": {"type": "directional", "direction": [0.3, 0.5, 0.8], "irradiance": [1, 1, 1]},
                               "camera": {"target": [0, 0, -0.1], "distance": 4, "elevation_deg": 10,
                                          "azimuth_deg": -10, "fov_y_deg": 30}})


def write_cable(out):
    pos, nrm, uv, idx = cable(4.0, 0.5, 0.012, 160, 8)
    lines = ["# shimmer scripts/generate-assets.py: a thin sagging cable", "mtllib cable.mtl", "o cable"]
    lines += ["v %s %s %s" % tuple(fmt(c) for c in p) for p in pos]
    lines += ["vn %s %s %s" % tuple(fmt(c) for c in n) for n in nrm]
    # OBJ's v grows up the image; shimmer flips it to glTF's convention.
    lines += ["vt %s %s" % (fmt(t[0]), fmt(1 - t[1])) for t in uv]
    lines.append("usemtl steel")
    for k in range(0, len(idx), 3):
        lines.append("f " + " ".join("%d/%d/%d" % ((i + 1,) * 3) for i in idx[k:k + 3]))
    write_text(os.path.join(out, "cable.obj"), "\n".join(lines) + "\n")
    write_text(os.path.join(out, "cable.mtl"),
               "# shimmer scripts/generate-assets.py\nnewmtl steel\nKd 0.5 0.5 0.5\nPr 0.1\nPm 1\n")
    write_scene(out, "cable", "thin mesh", {"assets": [{"file": "cable.obj"}],
                               "light": {"type": "directional", "direction": [0.2, 0.7, 0.7], "irradiance": [1, 1, 1]},
                               "material": "ggx:0.05",
                               "camera": {"target": [0, 0.75, 0], "distance": 5, "elevation_deg": 5, "azimuth_deg": 0,
                                          "fov_y_deg": 30}})


def write_tk19_fig1(out):
    g = Gltf()
    ground = g.mesh("ground", *quad(100.0))
    sphere = g.mesh("sphere 80", icosphere(1)[0], icosphere(1)[1], None, icosphere(1)[2])
    ring = g.mesh("torus 12x6", *torus(1.0, 0.4, 12, 6))
    g.node("ground", ground)
    # The props under one parent node, moved as a group: the loader must
    # compose the hierarchy's transforms.
    props = []
    for k, (x, z, r) in enumerate([(-1.6, 0.4, 0.45), (-0.4, -0.6, 0.6), (0.9, 0.3, 0.4), (2.0, -1.2, 0.55)]):
        props.append(g.node("sphere %d" % k, sphere, root=False, translation=[x, r, z], scale=[r, r, r]))
    props.append(g.node("ring", ring, root=False, translation=[0.3, 0.2, 1.6], scale=[0.5, 0.5, 0.5]))
    g.node("props", children=props, translation=[0.0, 0.0, -0.5])
    g.write_gltf(os.path.join(out, "tk19-fig1.gltf"))
    # The light 8 degrees above the horizon straight ahead of the camera, which
    # looks 6 degrees down: the ground's mirror glint lies 8 degrees below the
    # horizon, inside the view, where every half vector near it is grazing.
    el = math.radians(8)
    write_scene(out, "tk19-fig1", "grazing plane and low-poly meshes", {
        "assets": [{"file": "tk19-fig1.gltf"}],
        "light": {"type": "directional", "direction": [0, float(fmt(math.sin(el))), float(fmt(-math.cos(el)))],
                  "irradiance": [1, 1, 1]},
        "material": "ggx:0.01",
        "camera": {"target": [0, 0.4, -0.5], "distance": 8, "elevation_deg": 6, "azimuth_deg": -10, "fov_y_deg": 30}})


def write_bench_torus(out):
    """320 x 160 quads: 102,400 triangles, for the renderer's mesh aims."""
    write_torus_shot(out, "torus-100k", "fine mesh", 320, 160, glb=True)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--bench":
        os.makedirs(sys.argv[2], exist_ok=True)
        write_bench_torus(sys.argv[2])
        return
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "experiments", "scenes")
    os.makedirs(out, exist_ok=True)
    write_torus_shot(out, "torus-lowpoly", "low-poly mesh", 12, 6, glb=False)
    write_torus_shot(out, "torus-fine", "fine mesh", 192, 96, glb=True)
    write_panel(out)
    write_cable(out)
    write_tk19_fig1(out)


if __name__ == "__main__":
    main()
