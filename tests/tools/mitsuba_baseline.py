#!/usr/bin/env python3
"""Measures Mitsuba 3's own error and speed on the bundled scenes.

For each scene: render with Mitsuba 3 (scalar_rgb, box filter, the reference's
resolution and max_depth) at N spp with several seeds, and compute both relMSE
forms (docs/report.md) against the committed 4096-spp reference. Writes a JSON
that the agreement test (tests/core/render/mitsuba_agreement_test.cpp) and the
benchmark read, so CI never needs Mitsuba itself.

  pip install mitsuba==3.9.1
  python3 tests/tools/mitsuba_baseline.py --spp 16 --seeds 4 --out scenes/references/mitsuba_baseline.json
"""
import argparse, json, os, re, sys, tempfile, time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# scene id -> (xml, reference, params) as the references were rendered
SCENES = {
    "cbox": ("scenes/cbox/cbox-rgb.xml", "scenes/references/cbox_256_box_4096spp.exr", {"res": 256}),
    "cornell-box": ("scenes/cornell-box/scene.xml", "scenes/references/cornell-box_256_box_4096spp.exr",
                    {"resx": 256, "resy": 256}),
    "veach-mis": ("scenes/veach-mis/scene.xml", "scenes/references/veach-mis_320x180_box_4096spp.exr",
                  {"resx": 320, "resy": 180}),
    "matpreview": ("scenes/matpreview/matpreview.xml", "scenes/references/matpreview_256x192_box_4096spp.exr",
                   {"width": 256, "height": 192}),
}


def trimmed_rel_mse(img, ref, frac=0.005):
    """Per-pixel relMSE without the worst `frac` of pixel terms. Fireflies make
    the plain relMSE of scenes like veach-mis vary several-fold between seeds;
    a bias moves the body of the distribution, which this keeps."""
    e = ((img[..., :3].astype(np.float64) - ref[..., :3]) ** 2 / (ref[..., :3].astype(np.float64) ** 2 + 0.01)).ravel()
    e.sort()
    return float(e[: int(len(e) * (1.0 - frac))].mean())


def rel_mse(img, ref):
    img = img[..., :3].astype(np.float64)
    ref = ref[..., :3].astype(np.float64)
    glob = float(np.sum((img - ref) ** 2) / np.sum(ref ** 2))
    per_pixel = float(np.mean((img - ref) ** 2 / (ref ** 2 + 0.01)))
    return glob, per_pixel


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--out", default=os.path.join(ROOT, "scenes/references/mitsuba_baseline.json"))
    args = ap.parse_args()

    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    result = {"mitsuba": mi.__version__, "variant": "scalar_rgb", "spp": args.spp, "seeds": args.seeds,
              "threads": os.cpu_count(), "scenes": {}}
    for name in args.scenes.split(","):
        xml, ref_path, params = SCENES[name]
        ref = np.array(mi.Bitmap(os.path.join(ROOT, ref_path)), dtype=np.float32)
        src = open(os.path.join(ROOT, xml)).read()
        src = re.sub(r'<rfilter type="[^"]*"\s*/>', '<rfilter type="box"/>', src)
        d = os.path.dirname(os.path.join(ROOT, xml))
        fd, tmp = tempfile.mkstemp(suffix=".xml", dir=d)
        with os.fdopen(fd, "w") as f:
            f.write(src)
        try:
            scene = mi.load_file(tmp, spp=args.spp, **params)
        finally:
            os.unlink(tmp)
        globs, pps, trims, secs = [], [], [], []
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            img = np.array(mi.render(scene, seed=seed, spp=args.spp))
            secs.append(time.perf_counter() - t0)
            g, p = rel_mse(img, ref)
            globs.append(g)
            pps.append(p)
            trims.append(trimmed_rel_mse(img, ref))
        result["scenes"][name] = {
            "width": int(ref.shape[1]), "height": int(ref.shape[0]),
            # Medians over seeds: veach-mis's error is heavy-tailed (fireflies
            # from the small bright sphere), so means over a few seeds are unstable.
            "relmse_global_median": float(np.median(globs)), "relmse_global_mean": float(np.mean(globs)),
            "relmse_per_pixel_median": float(np.median(pps)), "relmse_per_pixel_mean": float(np.mean(pps)),
            "relmse_per_pixel_all": [float(x) for x in pps],
            "relmse_per_pixel_trimmed_median": float(np.median(trims)),
            "seconds_median": float(np.median(secs)),
        }
        print(name, json.dumps(result["scenes"][name]), flush=True)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    sys.exit(main())
