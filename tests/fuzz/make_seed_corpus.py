#!/usr/bin/env python3
"""Regenerates the committed seed corpus of the fuzz targets (tests/fuzz/corpus/)
from the bundled scenes and a few hand-written minimal inputs. Run from anywhere:

  python3 tests/fuzz/make_seed_corpus.py

Seeds are small on purpose: libFuzzer mutates them, and each run starts from
them (tests/fuzz/run_fuzz.sh keeps what it finds in build-fuzz, not here).
"""
import base64, json, os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CORPUS = os.path.join(HERE, "corpus")


def put(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def mitsuba_seeds():
    for rel in ["scenes/cbox/cbox-rgb.xml", "scenes/demo/cbox_demo.xml", "scenes/veach-mis/scene.xml",
                "scenes/cornell-box/scene.xml", "scenes/matpreview/matpreview.xml",
                "scenes/cbox/fragments/bsdfs-rgb.xml", "scenes/veach-mis/scene-v0.5.xml"]:
        with open(os.path.join(ROOT, rel), "rb") as f:
            put("mitsuba_xml", rel.replace("/", "_"), f.read())
    # Self-contained: every shape, BSDF and emitter kind the loader knows, plus
    # meshes from tests/fuzz/assets (the target's base folder and asset root).
    put("mitsuba_xml", "all_plugins.xml", """<scene version="3.0.0">
  <default name="spp" value="4"/>
  <integrator type="path"><integer name="max_depth" value="5"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
  </sensor>
  <bsdf type="diffuse" id="d"><rgb name="reflectance" value="0.5, 0.4, 0.3"/></bsdf>
  <bsdf type="roughconductor" id="c"><string name="material" value="Au"/><float name="alpha" value="0.1"/></bsdf>
  <bsdf type="dielectric" id="g"><float name="int_ior" value="1.5"/></bsdf>
  <bsdf type="roughplastic" id="p"><float name="alpha" value="0.2"/></bsdf>
  <bsdf type="twosided" id="t"><bsdf type="diffuse"/></bsdf>
  <shape type="rectangle"><ref id="d"/><transform name="to_world"><scale value="2"/><rotate x="1" angle="90"/></transform></shape>
  <shape type="cube" id="box"><ref id="c"/><transform name="to_world"><translate value="1,0,0"/></transform></shape>
  <shape type="sphere"><point name="center" value="0,1,0"/><float name="radius" value="0.5"/><ref id="g"/></shape>
  <shape type="disk"><ref id="p"/></shape>
  <shape type="obj"><string name="filename" value="tiny.obj"/><ref id="t"/></shape>
  <shape type="ply"><string name="filename" value="tiny.ply"/><ref id="d"/>
    <emitter type="area"><rgb name="radiance" value="10"/></emitter></shape>
  <emitter type="point"><point name="position" value="0,3,0"/><rgb name="intensity" value="5"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
</scene>
""")
    put("mitsuba_xml", "minimal.xml", '<scene version="3.0.0"><shape type="sphere"/></scene>\n')


def gltf_inline(path):
    """The glTF with its .bin buffers inlined as data URIs and images dropped."""
    with open(path) as f:
        g = json.load(f)
    base = os.path.dirname(path)
    for b in g.get("buffers", []):
        if "uri" in b and not b["uri"].startswith("data:"):
            with open(os.path.join(base, b["uri"]), "rb") as f:
                b["uri"] = "data:application/octet-stream;base64," + base64.b64encode(f.read()).decode()
    for key in ["images", "textures", "samplers"]:
        g.pop(key, None)
    for m in g.get("materials", []):
        pbr = m.get("pbrMetallicRoughness", {})
        for k in ["baseColorTexture", "metallicRoughnessTexture"]:
            pbr.pop(k, None)
        for k in ["normalTexture", "occlusionTexture", "emissiveTexture"]:
            m.pop(k, None)
    return json.dumps(g, separators=(",", ":"))


def gltf_seeds():
    for rel in ["scenes/gltf/AnimatedTriangle/AnimatedTriangle.gltf", "scenes/gltf/BoxAnimated/BoxAnimated.gltf",
                "scenes/gltf/AnimatedCube/AnimatedCube.gltf"]:
        put("gltf", os.path.basename(rel), gltf_inline(os.path.join(ROOT, rel)))
    # A one-triangle .glb with a camera and a point light.
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    binary = pos + idx
    g = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
         "nodes": [{"mesh": 0, "name": "tri"}, {"camera": 0, "translation": [0, 0, 3]},
                   {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 0]}],
         "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
         "extensionsUsed": ["KHR_lights_punctual"],
         "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10}]}},
         "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
         "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "roughnessFactor": 0.5}}],
         "buffers": [{"byteLength": len(binary)}],
         "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                         {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
         "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]},
                       {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
    js = json.dumps(g, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    chunks = struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(binary), b"BIN\0") + binary
    put("gltf", "triangle.glb", struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def job_seeds():
    with open(os.path.join(ROOT, "scenes/demo/demo_job.json"), "rb") as f:
        put("job_spec", "demo_job.json", f.read())
    put("job_spec", "minimal.json", '{"scene": "a.xml"}')
    put("job_spec", "full.json", json.dumps({
        "scene": "s.xml", "frames": "1-10x2,15", "fps": 23.976, "width": 64, "height": 32, "spp": 4,
        "time_budget_s": 0.5, "seed": 7, "integrator": "gpt", "shift": "hybrid",
        "reconstruction": {"method": "l1", "alpha": 0.1, "window": 3}, "params": {"res": 64, "x": "y"},
        "animation": {"tracks": [{"target": "box", "interpolation": "cubic", "keys": [
            {"frame": 0, "translate": [0, 0, 0], "rotate": {"axis": [0, 1, 0], "angle": 0}, "scale": [1, 1, 1]},
            {"frame": 9, "translate": [1, 2, 3]}]}]},
        "outputs": {"exr_layers": ["primal"], "previews": False, "video_codec": "none"},
        "priority": 3, "reference": "ref_%04d.exr"}))
    for i, fr in enumerate(["0", "1-100", "1-100x7", "1,5,10-20", " 3 - 4 ", "0-999999x1000"]):
        put("job_spec", "frames_%d.txt" % i, fr)


def mesh_seeds():
    for name in ["cbox_smallbox.obj", "cbox_luminaire.obj"]:
        with open(os.path.join(ROOT, "scenes/cbox/meshes", name), "rb") as f:
            put("obj", name, f.read())
    with open(os.path.join(HERE, "assets/tiny.obj"), "rb") as f:
        put("obj", "tiny.obj", f.read())
    put("obj", "negative_indices.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf -3/-1/-1 -2/-1/-1 -1/-1/-1\n")
    with open(os.path.join(HERE, "assets/tiny.ply"), "rb") as f:
        put("ply", "tiny_ascii.ply", f.read())
    for fmt, end in [("binary_little_endian", "<"), ("binary_big_endian", ">")]:
        head = ("ply\nformat %s 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n"
                "element face 1\nproperty list uchar int vertex_indices\nend_header\n" % fmt).encode()
        verts = b"".join(struct.pack(end + "8f", *v) for v in
                         [(0, 0, 0, 0, 0, 1, 0, 0), (1, 0, 0, 0, 0, 1, 1, 0), (0, 1, 0, 0, 0, 1, 0, 1)])
        put("ply", "tri_%s.ply" % fmt, head + verts + struct.pack(end + "B3i", 3, 0, 1, 2))
    # .serialized: first byte = shape index; then the file (version 4, two
    # meshes: float with normals+uvs, double without).
    def mesh(flags, name, verts, tris, double):
        f = "d" if double else "f"
        body = struct.pack("<I", flags) + name + b"\0" + struct.pack("<QQ", len(verts), len(tris))
        body += b"".join(struct.pack("<3" + f, *v) for v in verts)
        if flags & 1:
            body += b"".join(struct.pack("<3" + f, 0, 0, 1) for _ in verts)
        if flags & 2:
            body += b"".join(struct.pack("<2" + f, v[0], v[1]) for v in verts)
        body += b"".join(struct.pack("<3I", *t) for t in tris)
        return struct.pack("<HH", 0x041C, 4) + zlib.compress(body)
    tri = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    m0 = mesh(0x1000 | 1 | 2, b"a", tri, [(0, 1, 2)], False)
    m1 = mesh(0x2000, b"b", tri + [(1, 1, 0)], [(0, 1, 2), (1, 3, 2)], True)
    data = m0 + m1 + struct.pack("<QQI", 0, len(m0), 2)
    put("serialized", "two_meshes_0", b"\0" + data)
    put("serialized", "two_meshes_1", b"\1" + data)


if __name__ == "__main__":
    # Regenerate the seeds; keep the crash inputs the fuzzers found (their
    # regression tests live in tests/core/...), named *crash-*.
    for d, _, files in os.walk(CORPUS):
        for f in files:
            if "crash-" not in f:
                os.remove(os.path.join(d, f))
    mitsuba_seeds()
    gltf_seeds()
    job_seeds()
    mesh_seeds()
    n = sum(len(fs) for _, _, fs in os.walk(CORPUS))
    print("seed corpus: %d files in %s" % (n, CORPUS))
