"""The peer of fit-bench: the same fits by scipy.optimize.least_squares.

Reads one JSON problem on stdin (the geometry terms the Rust engine
precomputes, targets, weights, start, bounds), fits with method 'trf' and
scipy's default tolerances and 2-point Jacobian, and prints one JSON object:
seconds (median over `repeats` least_squares calls), params, cost (sum of squared
residuals), nfev. The models are the parameter-dependent parts of
brdf/src/*.rs, vectorised with numpy; fit-bench checks that they agree
with the Rust models before it trusts the comparison.
"""

import json
import sys
import time

import numpy as np
from scipy.optimize import least_squares

PI = np.pi


def pow_geo(ln_base, e):
    """base**e from ln(base) (-inf where base <= 0), as the engine does."""
    out = np.zeros_like(ln_base)
    m = np.isfinite(ln_base)
    out[m] = np.exp(e * ln_base[m])
    return out


def pow_pos(base, e):
    out = np.zeros_like(base)
    m = base > 0
    out[m] = np.exp(e * np.log(base[m]))
    return out


def ln_pos(x):
    out = np.full_like(x, -np.inf)
    m = x > 0
    out[m] = np.log(x[m])
    return out


def schlick(u, r0):
    k = (1.0 - np.clip(u, 0.0, 1.0)) ** 5
    return r0 * (1.0 - k) + k


def smith_g1(tan, alpha):
    at = alpha * tan
    out = np.ones_like(tan)
    m = at > 1.0 / 1.6
    a = 1.0 / at[m]
    out[m] = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return out


def model(name, g, p):
    if name == "lambert":
        (kd,) = p
        return np.full_like(g["cos_i"], kd / PI)
    if name == "retro-phong":
        kd, n, k1, k2, k3, k4 = p
        omc = 1.0 - g["cos_i"]
        kr = k1 * omc + k2
        ks = k3 * np.exp(k4 * omc)
        norm = (n + 2.0) / (2.0 * PI)
        return kd / PI + ks * norm * pow_geo(g["ln_mirror"], n) + kr * norm * pow_geo(g["ln_c"], n)
    if name == "abc-retro":
        kd, r0, ab, bb, cb, ar, br, cr = p
        spec = ar / (1.0 + br * (1.0 - g["nh"])) ** cr * schlick(g["vh"], r0)
        retro = ab / (1.0 + bb * (1.0 - g["c"])) ** cb * schlick(g["vpb"], r0)
        return kd / PI + spec + retro
    if name == "abc-retro-per-lobe":
        kd, r0_b, ab, bb, cb, r0_r, ar, br, cr = p
        spec = ar / (1.0 + br * (1.0 - g["nh"])) ** cr * schlick(g["vh"], r0_r)
        retro = ab / (1.0 + bb * (1.0 - g["c"])) ** cb * schlick(g["vpb"], r0_b)
        return kd / PI + spec + retro
    if name == "beckmann-retro":
        kd, alpha, r0 = p
        c = g["c"]
        out = np.full_like(c, kd / PI)
        m = (c >= 1e-4) & (g["cos_i"] > 0) & (g["cos_o"] > 0)
        cm = c[m]
        a2 = alpha * alpha
        c2 = cm * cm
        d = np.exp((c2 - 1.0) / (a2 * c2)) / (a2 * PI * c2 * c2)
        sh = smith_g1(g["tan_i"][m], alpha) * smith_g1(g["tan_o"][m], alpha)
        out[m] += d * schlick(g["vpb"][m], r0) * sh / (4.0 * g["cos_i"][m] * g["cos_o"][m])
        return out
    if name == "blinn-retro":
        kd, alpha_r, alpha_b = p
        return kd / PI + pow_geo(g["ln_nh"], alpha_r) + pow_geo(g["ln_c"], alpha_b)
    if name == "lafortune":
        kd, cxy_s, cz_s, n_s, cxy_r, cz_r, n_r = p
        lobe = lambda cxy, cz, n: pow_pos(cxy * g["lv_xy"] + cz * g["lv_z"], n)
        return kd / PI + lobe(cxy_s, cz_s, n_s) + lobe(cxy_r, cz_r, n_r)
    if name == "oren-nayar":
        rho, sigma = p
        s2 = sigma * sigma
        a = 1.0 - 0.5 * s2 / (s2 + 0.33)
        b = 0.45 * s2 / (s2 + 0.09)
        return rho / PI * (a + b * g["oren_nayar"])
    if name == "five-param":
        kb, kr, a, b, kd = p
        kr2 = kr * kr
        ca = g["nh"]
        d = kr2 * ca / ((kr2 - 1.0) * ca * ca + 1.0)
        return kb * d * np.exp(b * pow_geo(g["ln_one_minus_cos_gamma"], a)) * g["zhang_g_over_cos_o"] + kd
    raise SystemExit(f"unknown model {name}")


def versions():
    """The peer's versions and its BLAS, for the benchmark's JSON."""
    import scipy

    blas = {}
    try:
        cfg = np.show_config(mode="dicts")
        b = cfg["Build Dependencies"]["blas"]
        blas = {"name": b.get("name"), "version": b.get("version")}
    except Exception as e:  # older numpy: no dict mode
        blas = {"error": str(e)}
    return {"scipy": scipy.__version__, "numpy": np.__version__, "blas": blas}


def main():
    job = json.load(sys.stdin)
    if job.get("versions"):
        print(json.dumps(versions()))
        return
    g = {k: np.asarray(v, dtype=float) for k, v in job["geometry"].items()}
    # Parameter-independent logarithms, computed before the clock starts (the engine keeps them in Geometry).
    for k in ("mirror", "nh", "c", "one_minus_cos_gamma"):
        g["ln_" + k] = ln_pos(g[k])
    y = np.asarray(job["y"], dtype=float)
    w = np.asarray(job["weight"], dtype=float)
    scale = np.asarray(job["scale"], dtype=float)
    name = job["model"]
    if "check" in job:
        print(json.dumps({"values": model(name, g, np.asarray(job["check"], dtype=float)).tolist()}))
        return

    def residuals(p):
        r = w * (scale * model(name, g, p) - y)
        return np.where(np.isfinite(r), r, 1e150)

    if "starts" in job:
        # Multi-start: a plain least_squares from each start, the best kept,
        # the total time reported (the peer of the engine's global search).
        best, failed, t0 = None, 0, time.perf_counter()
        with np.errstate(all="ignore"):
            for s in job["starts"]:
                try:
                    res = least_squares(residuals, np.asarray(s), bounds=(job["lo"], job["hi"]), method="trf")
                except ValueError:  # a start where the residuals overflow
                    failed += 1
                    continue
                if best is None or res.cost < best.cost:
                    best = res
        seconds = time.perf_counter() - t0
        r = w * (scale * model(name, g, best.x) - y)
        print(json.dumps({"seconds": seconds, "params": best.x.tolist(), "cost": float(np.sum(r * r)), "failed_starts": failed}))
        return
    times = []
    for _ in range(job.get("repeats", 1)):
        t0 = time.perf_counter()
        res = least_squares(residuals, np.asarray(job["start"]), bounds=(job["lo"], job["hi"]), method="trf")
        times.append(time.perf_counter() - t0)
    seconds = float(np.median(times))
    r = w * (scale * model(name, g, res.x) - y)
    print(json.dumps({"seconds": seconds, "params": res.x.tolist(), "cost": float(np.sum(r * r)), "nfev": int(res.nfev)}))


if __name__ == "__main__":
    main()
