"""Renders an RGL `.bsdf` file with Mitsuba 3 (gonio's `render` module and
`render-check` run it; `pip install mitsuba`).

    python3 render_bsdf.py JOB

JOB (JSON, the argument itself): {"file": PATH.bsdf, "scenes": [SCENE, ...], "png_dir": DIR or null}.
A scene is a plane z = 0 of the material under an orthographic camera at
`origin` looking at the origin (`up`, `half` the half-side of the square it
sees) and a point light at `light` of radiant intensity `intensity`. Prints
{"mitsuba": VERSION, "means": [mean radiance of each image]} and, with a
`png_dir`, writes each image as NAME.png (sRGB), every one at the same
exposure (the brightest image's 99th percentile), so that they compare.
"""
import json
import os
import sys

import mitsuba as mi
import numpy as np

VARIANT = "scalar_spectral"
SIDE = 128


def render(path, scene):
    T = mi.ScalarTransform4f
    camera = T().look_at(origin=scene["origin"], target=[0, 0, 0], up=scene["up"]) @ T().scale([scene["half"], scene["half"], 1])
    description = {
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": {
            "type": "orthographic",
            "to_world": camera,
            "film": {"type": "hdrfilm", "width": SIDE, "height": SIDE, "pixel_format": "luminance", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 16},
        },
        "plane": {"type": "rectangle", "to_world": T().scale([20, 20, 1]), "bsdf": {"type": "measured", "filename": path}},
        "light": {"type": "point", "position": scene["light"], "intensity": {"type": "uniform", "value": scene["intensity"]}},
    }
    return np.array(mi.render(mi.load_dict(description)))


def save_png(image, scale, path):
    exposed = np.clip(image / scale, 0.0, 1.0).astype(np.float32)
    mi.util.write_bitmap(path, np.repeat(exposed, 3, axis=2), write_async=False)


def main(job):
    mi.set_variant(VARIANT)
    mi.set_log_level(mi.LogLevel.Warn)
    job = json.loads(job)
    images = [render(job["file"], scene) for scene in job["scenes"]]
    means = [float(np.mean(image)) for image in images]
    if job.get("png_dir"):
        scale = max(float(np.percentile(image, 99)) for image in images) or 1.0
        for scene, image in zip(job["scenes"], images):
            save_png(image, scale, os.path.join(job["png_dir"], scene["name"] + ".png"))
    print(json.dumps({"mitsuba": mi.__version__, "means": means}))


if __name__ == "__main__":
    main(sys.argv[1])
