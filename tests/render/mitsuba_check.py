"""Mitsuba 3's side of `render-check` (tests/src/bin/render_check.rs).

Reads the cases the Rust side wrote (each a `.bsdf` file, direction pairs,
retro directions and scenes), loads every file with Mitsuba's `measured`
plugin in the `scalar_spectral` variant, evaluates it at the pairs and the
retro directions, renders each scene, and writes what Mitsuba gave. The
comparison with our model is the Rust side's.
"""
import json
import sys

import mitsuba as mi
import numpy as np

VARIANT = "scalar_spectral"


def evaluate(bsdf, wi, wo):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wi)
    si.wavelengths = mi.Spectrum(550.0)
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wo))
    return float(value[0])


def render(path, scene):
    T = mi.ScalarTransform4f
    camera = T().look_at(origin=scene["origin"], target=[0, 0, 0], up=scene["up"]) @ T().scale([scene["half"], scene["half"], 1])
    description = {
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": {
            "type": "orthographic",
            "to_world": camera,
            "film": {"type": "hdrfilm", "width": 32, "height": 32, "pixel_format": "luminance", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 64},
        },
        "plane": {"type": "rectangle", "to_world": T().scale([20, 20, 1]), "bsdf": {"type": "measured", "filename": path}},
        "light": {"type": "point", "position": scene["light"], "intensity": {"type": "uniform", "value": scene["intensity"]}},
    }
    image = mi.render(mi.load_dict(description))
    return float(np.mean(np.array(image)))


def main(cases_path, out_path):
    mi.set_variant(VARIANT)
    mi.set_log_level(mi.LogLevel.Warn)
    data = json.load(open(cases_path))
    out = {"version": mi.__version__, "variant": VARIANT, "cases": {}}
    for case in data["cases"]:
        bsdf = mi.load_dict({"type": "measured", "filename": case["file"]})
        pairs = [evaluate(bsdf, wi, wo) for wi, wo in case["pairs"]]
        retro = [evaluate(bsdf, w, w) for w in case["retro"]]
        images = [render(case["file"], s) for s in data["scenes"]]
        out["cases"][case["name"]] = {"pairs": pairs, "retro": retro, "images": images}
        print(f"mitsuba {mi.__version__}: {case['name']} evaluated and rendered", file=sys.stderr)
    json.dump(out, open(out_path, "w"))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
