"""Mitsuba 3's side of `render-check` (bench/src/bin/render_check.rs).

Reads the cases the Rust side wrote (each a `.bsdf` file, direction pairs
and retro directions), loads every file with Mitsuba's `measured` plugin in
the `scalar_spectral` variant, evaluates it at the pairs and the retro
directions, and writes what Mitsuba gave. The comparison with our model is
the Rust side's; the pictures are drawn by gonio's own renderer script
(host/analysis/assets/render_bsdf.py).
"""
import json
import sys

import mitsuba as mi

VARIANT = "scalar_spectral"


def evaluate(bsdf, wi, wo):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wi)
    si.wavelengths = mi.Spectrum(550.0)
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*wo))
    return float(value[0])


def main(cases_path, out_path):
    mi.set_variant(VARIANT)
    mi.set_log_level(mi.LogLevel.Warn)
    data = json.load(open(cases_path))
    out = {"version": mi.__version__, "variant": VARIANT, "cases": {}}
    for case in data["cases"]:
        bsdf = mi.load_dict({"type": "measured", "filename": case["file"]})
        pairs = [evaluate(bsdf, wi, wo) for wi, wo in case["pairs"]]
        retro = [evaluate(bsdf, w, w) for w in case["retro"]]
        out["cases"][case["name"]] = {"pairs": pairs, "retro": retro}
        print(f"mitsuba {mi.__version__}: {case['name']} evaluated", file=sys.stderr)
    json.dump(out, open(out_path, "w"))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
