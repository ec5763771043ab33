"""Random Mitsuba 3 scenes from the subset gdvr supports, for differential
testing against Mitsuba itself (differential_test.py).

generate(seed, folder) writes folder/scene.xml (and the meshes, textures and
environment maps it names) and returns a short description. The same seed
gives the same files. The scenes are small rooms and boxes of `rectangle`,
`cube`, `disk`, `sphere` and OBJ shapes (with and without vertex normals), lit
by every emitter kind gdvr supports at random sizes, distances and powers
(very close to surfaces, very small, very bright), with every BSDF at random
parameters (alpha near 0 and 1, IOR near 1 and 3), checkerboard and bitmap
textures (PNG, JPEG, EXR), spectra given as values and lists, and max_depth
from 1 to unbounded.

Limits kept on purpose (each is a precision limit of the reference, not of
gdvr, and docs/correctness.md explains it):
- sphere lights subtend at least sin(alpha) ~ 0.005 from the surfaces that see
  them: Mitsuba's float cone sampling is off by up to ~1 % below that;
- point and spot lights stay 0.02 or more from surfaces (the 1/d^2 peak is a
  single pixel's business and makes block means depend on one sample).
"""
import math
import os
import random

import numpy as np

BSDF_TYPES = ["diffuse", "diffuse", "twosided-diffuse", "plastic", "roughplastic", "conductor", "roughconductor",
              "dielectric", "roughdielectric", "thindielectric"]
CONDUCTOR_MATERIALS = ["Au", "Ag", "Al", "Cu", "Cr", "none"]


def _fmt(v):
    return "%.6g" % v


def _rgb(values):
    return ", ".join(_fmt(v) for v in values)


class _Writer:
    def __init__(self, rng, folder):
        self.rng = rng
        self.folder = folder
        self.parts = []
        self.notes = []
        self.files = 0
        self.has_environment = False

    # ---- random numbers ----
    def u(self, a, b):
        return self.rng.uniform(a, b)

    def log_u(self, a, b):
        return math.exp(self.rng.uniform(math.log(a), math.log(b)))

    def pick(self, seq):
        return self.rng.choice(seq)

    def chance(self, p):
        return self.rng.random() < p

    # ---- colours ----
    def colour(self, name, lo=0.05, hi=0.95, within_emitter=False):
        kind = self.rng.random()
        if kind < 0.6:
            return '<rgb name="%s" value="%s"/>' % (name, _rgb([self.u(lo, hi) for _ in range(3)]))
        if kind < 0.75:
            return '<rgb name="%s" value="%s"/>' % (name, _fmt(self.u(lo, hi)))
        if kind < 0.88:
            return '<spectrum name="%s" value="%s"/>' % (name, _fmt(self.u(lo, hi)))
        # A smooth wavelength:value list inside [lo, hi].
        wl = sorted(self.rng.sample(range(380, 781, 20), self.rng.randint(2, 6)))
        pairs = ", ".join("%d:%s" % (w, _fmt(self.u(lo, hi))) for w in wl)
        return '<spectrum name="%s" value="%s"/>' % (name, pairs)

    def reflectance_texture(self, name):
        """A colour, a checkerboard or a bitmap."""
        r = self.rng.random()
        if r < 0.7:
            return self.colour(name)
        if r < 0.85:
            s = self.pick([1, 2, 5, 11])
            return ('<texture type="checkerboard" name="%s">%s%s<transform name="to_uv"><scale x="%d" y="%d"/>'
                    '</transform></texture>' % (name, self.colour("color0"), self.colour("color1"), s, s))
        return '<texture type="bitmap" name="%s"><string name="filename" value="%s"/>%s</texture>' % (
            name, self.bitmap(), self.pick(["", '<string name="filter_type" value="nearest"/>']))

    def bitmap(self):
        import mitsuba as mi
        h, w = self.pick([(4, 4), (8, 16), (32, 24)])
        y, x = np.mgrid[0:h, 0:w]
        img = np.stack([(x + 0.5) / w, (y + 0.5) / h, ((x + y) % 3) / 2.0], -1).astype(np.float32)
        img = 0.05 + 0.9 * img
        if self.chance(0.5):
            img = img[:, ::-1]
        ext = self.pick(["png", "jpg", "exr"])
        name = "tex%d.%s" % (self.files, ext)
        self.files += 1
        bmp = mi.Bitmap(np.ascontiguousarray(img))
        if ext != "exr":
            bmp = bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True)
        bmp.write(os.path.join(self.folder, name))
        return name

    # ---- BSDFs ----
    def alpha(self):
        r = self.rng.random()
        if r < 0.2:
            return self.log_u(0.001, 0.01)  # near specular
        if r < 0.35:
            return self.u(0.7, 1.0)  # near 1
        return self.log_u(0.01, 0.7)

    def ior(self):
        r = self.rng.random()
        if r < 0.2:
            return self.u(1.01, 1.1)  # near 1
        if r < 0.35:
            return self.u(2.5, 3.0)  # near 3
        return self.u(1.1, 2.5)

    def bsdf(self, kind=None, allow_glass=True):
        kinds = BSDF_TYPES if allow_glass else [k for k in BSDF_TYPES if "dielectric" not in k]
        kind = kind or self.pick(kinds)
        distribution = '<string name="distribution" value="%s"/>' % self.pick(["beckmann", "ggx"])
        if kind == "diffuse":
            return '<bsdf type="diffuse">%s</bsdf>' % self.reflectance_texture("reflectance")
        if kind == "twosided-diffuse":
            return '<bsdf type="twosided"><bsdf type="diffuse">%s</bsdf></bsdf>' % self.reflectance_texture("reflectance")
        if kind == "plastic":
            return '<bsdf type="plastic">%s<float name="int_ior" value="%s"/>%s</bsdf>' % (
                self.reflectance_texture("diffuse_reflectance"), _fmt(self.ior()),
                self.pick(["", '<boolean name="nonlinear" value="true"/>']))
        if kind == "roughplastic":
            return '<bsdf type="roughplastic">%s<float name="int_ior" value="%s"/><float name="alpha" value="%s"/>%s</bsdf>' % (
                self.reflectance_texture("diffuse_reflectance"), _fmt(self.ior()), _fmt(self.alpha()), distribution)
        if kind in ("conductor", "roughconductor"):
            mat = self.pick(CONDUCTOR_MATERIALS)
            body = '<string name="material" value="%s"/>' % mat
            if mat == "none" and self.chance(0.5):
                body = self.colour("eta", 0.1, 3.0) + self.colour("k", 0.5, 5.0)
            if self.chance(0.3):
                body += self.colour("specular_reflectance", 0.3, 1.0)
            if kind == "roughconductor":
                if self.chance(0.25):
                    body += '<float name="alpha_u" value="%s"/><float name="alpha_v" value="%s"/>' % (
                        _fmt(self.alpha()), _fmt(self.alpha()))
                else:
                    body += '<float name="alpha" value="%s"/>' % _fmt(self.alpha())
                body += distribution
            bsdf = '<bsdf type="%s">%s</bsdf>' % (kind, body)
            return '<bsdf type="twosided">%s</bsdf>' % bsdf if self.chance(0.3) else bsdf
        if kind == "dielectric":
            return '<bsdf type="dielectric"><float name="int_ior" value="%s"/></bsdf>' % _fmt(self.ior())
        if kind == "roughdielectric":
            return ('<bsdf type="roughdielectric"><float name="int_ior" value="%s"/><float name="alpha" value="%s"/>%s</bsdf>'
                    % (_fmt(self.ior()), _fmt(self.alpha()), distribution))
        if kind == "thindielectric":
            return '<bsdf type="thindielectric"><float name="int_ior" value="%s"/></bsdf>' % _fmt(self.ior())
        raise ValueError(kind)

    # ---- geometry ----
    def mesh(self, with_normals):
        """A closed, bumpy, convex-ish blob (subdivided octahedron) as OBJ."""
        verts = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
        faces = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
        verts = [np.array(v, float) for v in verts]
        for _ in range(2):
            cache, new_faces = {}, []

            def mid(a, b):
                key = (min(a, b), max(a, b))
                if key not in cache:
                    m = verts[a] + verts[b]
                    verts.append(m / np.linalg.norm(m))
                    cache[key] = len(verts) - 1
                return cache[key]

            for a, b, c in faces:
                ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
                new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
            faces = new_faces
        bump = [1.0 + 0.15 * self.rng.random() for _ in verts]
        pos = [v * s for v, s in zip(verts, bump)]
        name = "mesh%d.obj" % self.files
        self.files += 1
        with open(os.path.join(self.folder, name), "w") as f:
            for p in pos:
                f.write("v %s\n" % " ".join(_fmt(c) for c in p))
            for v in verts:
                f.write("vt %s %s\n" % (_fmt(0.5 + math.atan2(v[1], v[0]) / (2 * math.pi)), _fmt(0.5 + 0.5 * v[2])))
            if with_normals:
                for v in verts:
                    f.write("vn %s\n" % " ".join(_fmt(c) for c in v))
                for a, b, c in faces:
                    f.write("f %d/%d/%d %d/%d/%d %d/%d/%d\n" % (a + 1, a + 1, a + 1, b + 1, b + 1, b + 1, c + 1, c + 1, c + 1))
            else:
                for a, b, c in faces:
                    f.write("f %d/%d %d/%d %d/%d\n" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1))
        return name

    def transform(self, centre, scale, rotate=True):
        t = '<transform name="to_world"><scale value="%s"/>' % _fmt(scale)
        if rotate:
            # A unit axis: Mitsuba 3 does not normalise it (its matrix then
            # scales, and its normals are wrong); gdvr does.
            axis = np.array([self.u(-1, 1), self.u(-1, 1), self.u(0.1, 1)])
            axis /= np.linalg.norm(axis)
            t += '<rotate x="%s" y="%s" z="%s" angle="%s"/>' % (*(_fmt(c) for c in axis), _fmt(self.u(0, 360)))
        t += '<translate x="%s" y="%s" z="%s"/></transform>' % tuple(_fmt(c) for c in centre)
        return t

    def object(self, centre, size):
        kind = self.pick(["sphere", "cube", "obj", "obj-normals", "disk", "rectangle"])
        bsdf = self.bsdf()
        if kind == "sphere":
            self.parts.append('<shape type="sphere"><point name="center" x="%s" y="%s" z="%s"/>'
                              '<float name="radius" value="%s"/>%s</shape>' % (*(_fmt(c) for c in centre), _fmt(size), bsdf))
        elif kind in ("obj", "obj-normals"):
            self.parts.append('<shape type="obj"><string name="filename" value="%s"/>%s%s</shape>' % (
                self.mesh(kind == "obj-normals"), self.transform(centre, size), bsdf))
        else:
            self.parts.append('<shape type="%s">%s%s</shape>' % (kind, self.transform(centre, size), bsdf))
        self.notes.append("%s %s" % (kind, bsdf.split('"')[1] if "twosided" not in bsdf[:30] else "twosided"))


def _room(w, closed):
    """Walls of the box [-1, 1]^3 facing inwards (5 or 6)."""
    walls = [("x", -90, (0, -1, 0)), ("x", 90, (0, 1, 0)), ("y", 0, (0, 0, -1)), ("y", 90, (-1, 0, 0)),
             ("y", -90, (1, 0, 0))]
    if closed:
        walls.append(("y", 180, (0, 0, 1)))
    material = w.bsdf(w.pick(["diffuse", "twosided-diffuse", "twosided-diffuse"]))
    use_cubes = w.chance(0.2)
    for axis, angle, t in walls:
        if use_cubes:  # thin slabs instead of rectangles
            n = np.array(t, float)
            scale = np.where(n != 0, 0.02, 1.0)
            centre = n * 1.02
            w.parts.append('<shape type="cube"><transform name="to_world"><scale x="%s" y="%s" z="%s"/>'
                           '<translate x="%s" y="%s" z="%s"/></transform>%s</shape>'
                           % (*(_fmt(s) for s in scale), *(_fmt(c) for c in centre), material))
        else:
            w.parts.append('<shape type="rectangle"><transform name="to_world"><rotate %s="1" angle="%d"/>'
                           '<translate x="%s" y="%s" z="%s"/></transform>%s</shape>'
                           % (axis, angle, *(_fmt(c) for c in t), material))
    if w.chance(0.3):  # a partition
        w.parts.append('<shape type="cube"><transform name="to_world"><scale x="0.02" y="0.6" z="0.5"/>'
                       '<translate x="%s" y="-0.4" z="-0.3"/></transform>%s</shape>' % (_fmt(w.u(-0.5, 0.5)), material))


def _light(w, closed, room):
    """One emitter; returns its kind. A scene has at most one environment."""
    kinds = ["sphere", "sphere", "rectangle", "point", "spot", "disk"]
    if not (room and closed):
        kinds += ["directional"]
        if not w.has_environment:
            kinds += ["constant", "envmap", "envmap"]
    kind = w.pick(kinds)
    w.has_environment |= kind in ("constant", "envmap")
    power = w.log_u(0.5, 50.0)
    # Where: somewhere in the upper half, or very close to a wall or the floor.
    if w.chance(0.3):
        p = np.array([w.u(-0.7, 0.7), w.pick([-1, 1]) * w.u(0.85, 0.97), w.u(-0.7, 0.7)])
    else:
        p = np.array([w.u(-0.7, 0.7), w.u(0.0, 0.8), w.u(-0.7, 0.3)])
    radiance_note = ""
    if kind == "sphere":
        # Radius: tiny to large, but it subtends sin(alpha) >= ~0.005 from the room.
        r = w.pick([w.log_u(0.01, 0.05), w.log_u(0.05, 0.3)])
        gap = 1.0 - abs(p[1]) - r
        if gap < 0.002:
            p[1] = math.copysign(1.0 - r - w.log_u(0.002, 0.05), p[1])
        le = power / (math.pi * r * r)
        w.parts.append('<shape type="sphere"><point name="center" x="%s" y="%s" z="%s"/><float name="radius" value="%s"/>'
                       '<emitter type="area">%s</emitter></shape>'
                       % (*(_fmt(c) for c in p), _fmt(r), _emission(w, "radiance", le)))
        radiance_note = "r=%.3g" % r
    elif kind in ("rectangle", "disk"):
        s = w.log_u(0.02, 0.4)
        le = power / (4 * s * s)
        facing = w.pick([90, 90, 60, 120])  # mostly downwards
        bsdf = w.bsdf("diffuse") if w.chance(0.3) else ""
        w.parts.append('<shape type="%s"><transform name="to_world"><scale value="%s"/><rotate x="1" angle="%d"/>'
                       '<translate x="%s" y="%s" z="%s"/></transform>%s<emitter type="area">%s</emitter></shape>'
                       % (kind, _fmt(s), facing, *(_fmt(c) for c in p), bsdf, _emission(w, "radiance", le)))
        radiance_note = "size=%.3g" % s
    elif kind == "point":
        if abs(p[1]) > 0.98:
            p[1] = math.copysign(0.98, p[1])
        w.parts.append('<emitter type="point"><point name="position" x="%s" y="%s" z="%s"/>%s</emitter>'
                       % (*(_fmt(c) for c in p), _emission(w, "intensity", power / (4 * math.pi))))
    elif kind == "spot":
        p[1] = min(p[1], 0.9)
        target = (w.u(-0.5, 0.5), -1.0, w.u(-0.5, 0.5))
        cutoff = w.u(10, 80)
        w.parts.append('<emitter type="spot"><transform name="to_world"><lookat origin="%s" target="%s" up="0, 0, 1"/>'
                       '</transform><float name="cutoff_angle" value="%s"/><float name="beam_width" value="%s"/>%s</emitter>'
                       % (_rgb(p), _rgb(target), _fmt(cutoff), _fmt(cutoff * w.u(0.2, 1.0)),
                          _emission(w, "intensity", power)))
    elif kind == "directional":
        d = np.array([w.u(-0.6, 0.6), -1.0, w.u(-0.6, 0.6)])
        w.parts.append('<emitter type="directional"><vector name="direction" x="%s" y="%s" z="%s"/>%s</emitter>'
                       % (*(_fmt(c) for c in d), _emission(w, "irradiance", w.log_u(0.3, 5.0))))
    elif kind == "constant":
        w.parts.append('<emitter type="constant">%s</emitter>' % _emission(w, "radiance", w.log_u(0.1, 2.0)))
    elif kind == "envmap":
        w.parts.append('<emitter type="envmap"><string name="filename" value="%s"/><float name="scale" value="%s"/>'
                       '<transform name="to_world"><rotate y="1" angle="%s"/></transform></emitter>'
                       % (_envmap(w), _fmt(w.log_u(0.2, 3.0)), _fmt(w.u(0, 360))))
    return kind + (" " + radiance_note if radiance_note else "")


def _emission(w, name, level):
    r = w.rng.random()
    if r < 0.6:
        return '<rgb name="%s" value="%s"/>' % (name, _rgb([level * w.u(0.5, 1.0) for _ in range(3)]))
    if r < 0.85:
        return '<spectrum name="%s" value="%s"/>' % (name, _fmt(level))
    wl = sorted(w.rng.sample(range(380, 781, 40), w.rng.randint(2, 5)))
    return '<spectrum name="%s" value="%s"/>' % (name, ", ".join("%d:%s" % (x, _fmt(level * w.u(0.3, 1.5))) for x in wl))


def _envmap(w):
    import mitsuba as mi
    h, wd = w.pick([(8, 16), (16, 32), (32, 64)])
    y, x = np.mgrid[0:h, 0:wd]
    img = 0.2 + 0.3 * np.stack([np.sin(2 * np.pi * x / wd) ** 2, (y / h), np.cos(np.pi * y / h) ** 2], -1)
    # A small, bright "sun" texel block next to black ones.
    sy, sx = w.rng.randrange(1, h // 2), w.rng.randrange(wd)
    img[sy, sx] = w.log_u(20, 500)
    if w.chance(0.5):
        img[h // 2:] *= 0.0  # black lower half
    name = "env%d.exr" % w.files
    w.files += 1
    mi.Bitmap(np.ascontiguousarray(img.astype(np.float32))).write(os.path.join(w.folder, name))
    return name


def generate(seed, folder, width=48, height=48):
    """Writes folder/scene.xml for `seed`; returns a one-line description."""
    os.makedirs(folder, exist_ok=True)
    rng = random.Random(seed)
    w = _Writer(rng, folder)
    layout = w.pick(["open-box", "closed-room", "closed-room", "ground"])
    room = layout != "ground"
    closed = layout == "closed-room"
    max_depth = w.pick([1, 2, 3, 4, 6, 8, 12, -1, -1])
    if room:
        _room(w, closed)
    else:
        w.parts.append('<shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/>'
                       '<translate y="-1"/></transform>%s</shape>' % w.bsdf("diffuse"))
    lights = [_light(w, closed, room) for _ in range(w.pick([1, 1, 2, 3]))]
    for _ in range(w.pick([0, 1, 2, 3])):
        size = w.u(0.1, 0.35)
        centre = (w.u(-0.6, 0.6), -1.0 + size + w.u(0.0, 0.6), w.u(-0.6, 0.3))
        w.object(centre, size)
    if closed:
        origin = (w.u(-0.5, 0.5), w.u(-0.5, 0.3), w.u(0.5, 0.9))
    else:
        origin = (w.u(-0.8, 0.8), w.u(-0.3, 0.6), w.u(2.8, 4.0))
    target = (w.u(-0.3, 0.3), w.u(-0.5, 0.0), -1.0)
    fov = w.u(35, 75) if closed else w.u(30, 50)
    hide = '<boolean name="hide_emitters" value="true"/>' if w.chance(0.1) else ""
    xml = ['<scene version="3.0.0">',
           '<integrator type="path"><integer name="max_depth" value="%d"/>%s</integrator>' % (max_depth, hide),
           '<sensor type="perspective"><float name="fov" value="%s"/>'
           '<transform name="to_world"><lookat origin="%s" target="%s" up="0, 1, 0"/></transform>'
           '<sampler type="independent"><integer name="sample_count" value="16"/></sampler>'
           '<film type="hdrfilm"><integer name="width" value="%d"/><integer name="height" value="%d"/>'
           '<rfilter type="box"/></film></sensor>' % (_fmt(fov), _rgb(origin), _rgb(target), width, height)]
    xml += w.parts
    # Two specks (spheres of radius 1e-4, black) at the corners of the
    # scene's bounds. Mitsuba 3.9.1 merges meshes that share a BSDF and leaves
    # the merged mesh's bounding box invalid, so the scene's bounds (and the
    # sphere its environment and directional emitters place their samples on)
    # can miss the walls: environment light then leaked through them into
    # Mitsuba's references. The specks restore the bounds; both renderers see them.
    for corner in (-3.5, 3.5):
        xml.append('<shape type="sphere"><point name="center" x="%s" y="%s" z="%s"/><float name="radius" value="1e-4"/>'
                   '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></shape>' % ((_fmt(corner),) * 3))
    xml.append("</scene>")
    with open(os.path.join(folder, "scene.xml"), "w") as f:
        f.write("\n".join(xml) + "\n")
    return "%s max_depth=%d lights=[%s] objects=[%s]%s" % (layout, max_depth, "; ".join(lights), "; ".join(w.notes),
                                                          " hide_emitters" if hide else "")
