//! A fitted model as a Disney BRDF Explorer `.brdf` file: an `analytic`
//! header, one `float NAME MIN MAX DEFAULT` line per parameter (the model's
//! search bounds, the fitted value as default) and a GLSL function
//! `vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)`; a fitted rational
//! function (`write_rational`) with its coefficients in the GLSL and no
//! parameter line.
//!
//! The GLSL is the host's f64 model (`gonio_brdf`) written once more, in the
//! tool's language: it first takes `L` and `V` into the local frame `(X, Y, N)`
//! and then follows [`gonio_brdf::GeometryTerms`] and the model's `eval` line by
//! line, so that the tests can compile it as C++ (tests/tests/brdf_export.rs)
//! and compare it with the Rust model at many geometries. BRDF Explorer
//! multiplies by `n·l` itself: the function returns `f_r` (sr⁻¹), grey.

use crate::fit::Units;
use crate::rational::basis::Coordinates;
use crate::rational::Rational;
use gonio_brdf::{Material, ModelId, Param};
use std::fmt::Write;

/// Helpers shared by every model: the vectors of `Directions`, Schlick's
/// Fresnel and `max(0, base)^e` (GLSL's `pow` is undefined for a negative base).
const PRELUDE: &str = r"const float PI = 3.14159265358979323846;

vec3 unitSum(vec3 p, vec3 q)
{
    vec3 s = p + q;
    float len = length(s);
    return len < 1e-30 ? vec3(0.0, 0.0, 1.0) : s / len;
}

float posPow(float base, float e)
{
    return base > 0.0 ? pow(base, e) : 0.0;
}

float schlick(float u, float f0)
{
    float k = pow(1.0 - clamp(u, 0.0, 1.0), 5.0);
    return f0 * (1.0 - k) + k;
}

vec2 planar(vec3 w)
{
    return vec2(w.x, w.y);
}

// tan θ of a direction; its sine from the in-plane part, not sqrt(1 − cos²),
// which turns the rounding of a cosine near 1 into a sine of 1e-8.
float tanOf(vec3 w)
{
    return length(planar(w)) / max(w.z, 1e-9);
}
";

/// Local directions and the vectors every model may use.
const FRAME: &str = r"    vec3 l = vec3(dot(L, X), dot(L, Y), dot(L, N));
    vec3 v = vec3(dot(V, X), dot(V, Y), dot(V, N));
    float cosI = clamp(l.z, 0.0, 1.0);
    float cosO = clamp(v.z, 0.0, 1.0);
    if (l.z <= 0.0 || v.z <= 0.0) {
        return vec3(0.0);
    }
    vec3 hv = unitSum(l, v);
    vec3 vRefl = vec3(-v.x, -v.y, v.z);
    vec3 bk = unitSum(vRefl, l);
    float lv = clamp(dot(l, v), -1.0, 1.0);
";

/// Zhang et al.'s shadowing `G` (eq. 3–4, spherical-particle constants), as
/// `geometry::zhang_shadowing`. Where the half vector is within 1e-4 of the
/// normal its in-plane direction is float noise, so the limit form is taken
/// from there (the f64 code switches at 1e-9).
const ZHANG_SHADOWING: &str = r"
vec2 planarUnit(vec3 w)
{
    float r = length(planar(w));
    return r < 1e-30 ? vec2(1.0, 0.0) : planar(w) / r;
}

float zhangShadowing(vec3 l, vec3 v, vec3 hv, float cosGamma, float cosI, float tanI, float tanO)
{
    float cosAlpha = clamp(hv.z, 0.0, 1.0);
    float sinAlpha = length(planar(hv));
    float azI = 1.0;
    float azO = 1.0;
    float tanGamma = tanI / 2.0;
    if (sinAlpha >= 1e-4 && cosGamma >= 1e-12) {
        azI = dot(planar(hv), planarUnit(l)) / sinAlpha;
        azO = dot(planar(hv), planarUnit(v)) / sinAlpha;
        tanGamma = abs(cosI - cosGamma) / (2.0 * sinAlpha * cosGamma);
    }
    float w = 0.0136 * (1.0 + 9.0 * sinAlpha / (sinAlpha + 1.0 * cosAlpha));
    float ti = tanI * azI;
    float to = tanO * azO;
    return (1.0 + w * abs(ti * to) / (1.0 + 0.0141 * tanGamma)) / ((1.0 + w * ti * ti) * (1.0 + w * to * to));
}
";

/// Smith–Beckmann `G1` in Walter et al.'s rational form, as `beckmann_retro::smith_g1`.
const SMITH_G1: &str = r"
float smithG1(float tanT, float alphaB)
{
    float at = alphaB * tanT;
    if (at <= 1.0 / 1.6) {
        return 1.0;
    }
    float q = 1.0 / at;
    return (3.535 * q + 2.181 * q * q) / (1.0 + 2.276 * q + 2.577 * q * q);
}
";

/// Extra helper functions and the body (after [`FRAME`]) that sets `f`.
fn body(model: ModelId) -> (&'static str, &'static str) {
    match model {
        ModelId::Lambert => ("", "    float f = kd / PI;\n"),
        ModelId::RetroPhong => (
            "",
            r"    float oneMinusCos = 1.0 - cosI;
    float krT = k1 * oneMinusCos + k2;
    float ksT = k3 * exp(k4 * oneMinusCos);
    float norm = (n + 2.0) / (2.0 * PI);
    float mirrorCos = dot(vec3(-l.x, -l.y, l.z), v);
    float f = kd / PI + ksT * norm * posPow(mirrorCos, n) + krT * norm * posPow(retroCos, n);
",
        ),
        ModelId::AbcRetro => (
            "",
            r"    float specular = ar / pow(1.0 + br * (1.0 - hv.z), cr) * schlick(dot(v, hv), r0);
    float retro = ab / pow(1.0 + bb * (1.0 - retroCos), cb) * schlick(dot(vRefl, bk), r0);
    float f = kd / PI + specular + retro;
",
        ),
        ModelId::AbcRetroPerLobe => (
            "",
            r"    float specular = ar / pow(1.0 + br * (1.0 - hv.z), cr) * schlick(dot(v, hv), r0_r);
    float retro = ab / pow(1.0 + bb * (1.0 - retroCos), cb) * schlick(dot(vRefl, bk), r0_b);
    float f = kd / PI + specular + retro;
",
        ),
        ModelId::BeckmannRetro => (
            SMITH_G1,
            r"    float f = kd / PI;
    if (retroCos >= 1e-4 && cosI > 0.0 && cosO > 0.0) {
        float a2 = alpha * alpha;
        float c2 = retroCos * retroCos;
        float d = exp((c2 - 1.0) / (a2 * c2)) / (a2 * PI * c2 * c2);
        float shadowing = smithG1(tanOf(l), alpha) * smithG1(tanOf(v), alpha);
        f += d * schlick(dot(vRefl, bk), r0) * shadowing / (4.0 * cosI * cosO);
    }
",
        ),
        ModelId::BlinnRetro => ("", "    float f = kd / PI + posPow(hv.z, alpha_r) + posPow(retroCos, alpha_b);\n"),
        ModelId::Lafortune => (
            "",
            r"    float lvXY = l.x * v.x + l.y * v.y;
    float lvZ = l.z * v.z;
    float f = kd / PI + posPow(cxy_s * lvXY + cz_s * lvZ, n_s) + posPow(cxy_r * lvXY + cz_r * lvZ, n_r);
",
        ),
        ModelId::OrenNayar => (
            "",
            r"    float sinI = length(planar(l));
    float sinO = length(planar(v));
    float azNorm = length(planar(l)) * length(planar(v));
    float cosDphi = azNorm < 1e-30 ? 1.0 : clamp(dot(planar(l), planar(v)) / azNorm, -1.0, 1.0);
    float on = sinI > sinO ? max(cosDphi, 0.0) * sinI * tanOf(v) : max(cosDphi, 0.0) * sinO * tanOf(l);
    float s2 = sigma * sigma;
    float termA = 1.0 - 0.5 * s2 / (s2 + 0.33);
    float termB = 0.45 * s2 / (s2 + 0.09);
    float f = rho / PI * (termA + termB * on);
",
        ),
        ModelId::FiveParam => (
            ZHANG_SHADOWING,
            r"    float cosGamma = sqrt((1.0 + lv) / 2.0);
    float g = zhangShadowing(l, v, hv, cosGamma, cosI, tanOf(l), tanOf(v));
    float kr2 = kr * kr;
    float d = kr2 * hv.z / ((kr2 - 1.0) * hv.z * hv.z + 1.0);
    float fresnel = exp(b * posPow(1.0 - cosGamma, a));
    float f = kb * d * fresnel * g / max(cosO, 1e-9) + kd;
",
        ),
    }
}

/// The retro cosine the fit used, as a GLSL statement.
fn retro_cos(model: ModelId, param: Param) -> &'static str {
    match (model.has_retro_cosine(), param) {
        (false, _) => "",
        (true, Param::View) => "    float retroCos = max(lv, 0.0);\n",
        (true, Param::Back) => "    float retroCos = bk.z;\n",
    }
}

/// The `.brdf` text of a fitted material; `comments` go into the header
/// (source file, fit metrics), one `#` line each.
pub fn write(m: &Material, comments: &[String]) -> String {
    let mut header = vec![format!("{} fitted by gonio {}", m.model.name(), env!("CARGO_PKG_VERSION"))];
    if m.model.has_retro_cosine() {
        header.push(format!(
            "retro cosine: {}",
            if m.param == Param::View { "view (l·v)" } else { "back (n·b)" }
        ));
    }
    let mut parameters = String::new();
    for ((name, b), v) in m.model.param_names().iter().zip(m.model.bounds()).zip(&m.params) {
        let _ = writeln!(parameters, "float {name} {} {} {v}", b.lo.min(*v), b.hi.max(*v));
    }
    let (helpers, model_body) = body(m.model);
    let body = format!("{}{model_body}", retro_cos(m.model, m.param));
    document(&header, comments, &parameters, helpers, &body)
}

/// The `.brdf` text of a fitted rational function (`rational::Rational`),
/// its coefficients written into the shader: it has no parameter a user
/// would move. Its coordinates, box and Legendre terms follow
/// `rational::basis` line by line; where the denominator is not positive
/// (a pole, which the fit holds away from the samples and a grid only) it
/// returns 0, where the Rust function returns NaN.
pub fn write_rational(r: &Rational, comments: &[String]) -> String {
    let header = [
        format!(
            "rational function of degree {} ({} coefficients{}) fitted by gonio {}",
            r.degree,
            r.coefficients(),
            if r.cosine { ", times cosθi·cosθo" } else { "" },
            env!("CARGO_PKG_VERSION")
        ),
        format!("coordinates: {}", r.coordinates.name()),
    ];
    // The function was fitted with the light at azimuth 0 (`Directions`):
    // the light and the view turned about the normal to put it there. The
    // angle from the light is taken before the turn, which rounds: at the
    // retro peak the square-root warp would raise its 1e-16 to 1e-8. An
    // in-plane direction is taken by its unit vector, not by atan(0, 0),
    // which GLSL leaves undefined at the retro peak.
    let mut b = String::from(
        "    vec2 lPlanar = planar(l);\n    float sinI = length(lPlanar);\n    \
         vec2 az = sinI > 0.0 ? lPlanar / sinI : vec2(1.0, 0.0);\n    vec3 lr = vec3(sinI, 0.0, l.z);\n    \
         vec3 vr = vec3(az.x * v.x + az.y * v.y, az.x * v.y - az.y * v.x, v.z);\n    \
         float thetaI = degrees(atan(sinI, lr.z));\n",
    );
    // `Coordinates::of`: the angle and the direction of the view's place
    // in its plane, then the warp (none in ALTA's view plane, whose
    // azimuth is Δφ folded onto [0°, 180°]).
    b.push_str(match r.coordinates {
        Coordinates::Back => {
            "    vec3 back = unitSum(vec3(-v.x, -v.y, v.z), l);\n    \
             float theta = degrees(atan(length(planar(back)), back.z));\n    \
             vec2 w = planar(unitSum(vec3(-vr.x, -vr.y, vr.z), lr));\n"
        }
        Coordinates::LightView => {
            "    float theta = degrees(atan(length(cross(l, v)), dot(l, v)));\n    \
             vec2 w = vec2(dot(vr, vec3(-lr.z, 0.0, lr.x)), vr.y);\n"
        }
        Coordinates::ViewProjected => {
            "    float theta = degrees(atan(length(planar(vr)), vr.z));\n    \
             vec2 w = vec2(vr.x, abs(vr.y));\n"
        }
    });
    b.push_str(
        "    float wLength = length(w);\n    vec2 toward = wLength > 0.0 ? w / wLength : vec2(1.0, 0.0);\n    \
         float px = theta * toward.x;\n    float py = theta * toward.y;\n",
    );
    b.push_str(match r.coordinates {
        Coordinates::ViewProjected => "    float warp = 1.0;\n",
        _ => "    float radius = sqrt(px * px + py * py);\n    float warp = radius > 0.0 ? sqrt(radius) / radius : 0.0;\n",
    });
    for (k, c) in ["thetaI", "warp * px", "warp * py"].iter().enumerate() {
        let (lo, hi) = (r.domain.lo[k], r.domain.hi[k]);
        let _ = writeln!(
            b,
            "    float u{k} = clamp(2.0 * ({c} - ({lo:e})) / ({:e}) - 1.0, -1.0, 1.0);",
            hi - lo
        );
        // (n + 1) P_{n+1} = (2n + 1) x P_n − n P_{n−1}
        let _ = writeln!(b, "    float p{k}_0 = 1.0;");
        if r.degree >= 1 {
            let _ = writeln!(b, "    float p{k}_1 = u{k};");
        }
        for n in 1..r.degree {
            let _ = writeln!(
                b,
                "    float p{k}_{} = ({}.0 * u{k} * p{k}_{n} - {n}.0 * p{k}_{}) / {}.0;",
                n + 1,
                2 * n + 1,
                n - 1,
                n + 1
            );
        }
    }
    let basis = r.basis();
    for (name, coefficients) in [("numerator", &r.numerator), ("denominator", &r.denominator)] {
        let _ = writeln!(b, "    float {name} = 0.0;");
        for ([i, j, k], c) in basis.terms().iter().zip(coefficients.iter()) {
            let _ = writeln!(b, "    {name} += {c:e} * p0_{i} * p1_{j} * p2_{k};");
        }
    }
    b.push_str("    if (denominator <= 0.0) {\n        return vec3(0.0);\n    }\n");
    // `Rational::factor`, term for term.
    b.push_str(match (r.cosine, r.quantity) {
        (true, Units::Fr) => "    float f = cosI * cosO * numerator / denominator;\n",
        (true, Units::FrCos) => "    float f = cosI * numerator / denominator;\n",
        (false, Units::Fr) => "    float f = numerator / denominator;\n",
        (false, Units::FrCos) => "    float f = numerator / denominator / cosO;\n",
    });
    document(&header, comments, "", "", &b)
}

/// A whole `.brdf` file: header lines, the parameter block, the shader with
/// the prelude, `helpers`, and `BRDF` setting `f` in `body` after [`FRAME`].
fn document(header: &[String], comments: &[String], parameters: &str, helpers: &str, body: &str) -> String {
    let mut s = String::from("analytic\n\n");
    for c in header.iter().chain(comments) {
        let _ = writeln!(s, "# {}", c.replace('\n', " "));
    }
    s.push_str("# Returns f_r in 1/sr (BRDF Explorer applies n·l itself).\n\n::begin parameters\n");
    s.push_str(parameters);
    s.push_str("::end parameters\n\n::begin shader\n\n");
    s.push_str(PRELUDE);
    s.push_str(helpers);
    s.push_str("\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)\n{\n");
    s.push_str(FRAME);
    s.push_str(body);
    s.push_str("    return vec3(f);\n}\n\n::end shader\n");
    s
}
