//! The Disney BRDF Explorer export. Every model's `.brdf` file is
//! checked three ways: naga (pure Rust, so everywhere `cargo test` runs)
//! parses its GLSL as a fragment shader with the parameters as uniforms and
//! validates the module (types, names, calls, control flow); glslangValidator
//! compiles it as the tool would; and g++ compiles the same text as C++
//! against a small GLSL shim (tests/glsl/shim.hpp) so that it can be
//! evaluated and compared with the host's Rust model at the Belcour grid and
//! random geometries, seen from a random surface frame. CI installs the two
//! external tools and sets `GONIO_REQUIRE_GLSL_TOOLS`, so there a missing tool
//! fails the test; on a machine with only a Rust toolchain (the README's
//! `cargo test`) the steps whose tool is missing are skipped and said so on
//! stderr, while the parameter blocks and naga's check still run.

use gonio_analysis::fit::Units;
use gonio_analysis::formats::brdf_explorer;
use gonio_analysis::moments::Parametrization;
use gonio_analysis::rational::basis::{Basis, Coordinates, Domain};
use gonio_analysis::rational::{self, Rational, RationalSpec, SegmentSource};
use gonio_brdf::{Directions, GlassBeads, Material, ModelId, Param};
use gonio_tests::synthetic;
use rand::{Rng, SeedableRng};
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

/// The `float NAME MIN MAX DEFAULT` lines of a `.brdf` file.
fn parameters(text: &str) -> Vec<(String, f64, f64, f64)> {
    let start = text.find("::begin parameters\n").expect("parameter block") + "::begin parameters\n".len();
    let end = text.find("::end parameters").expect("end of the parameter block");
    text[start..end]
        .lines()
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(w.len(), 5, "parameter line `{l}`");
            assert_eq!(w[0], "float");
            let num = |s: &str| s.parse::<f64>().unwrap_or_else(|_| panic!("`{s}` in `{l}`"));
            (w[1].to_string(), num(w[2]), num(w[3]), num(w[4]))
        })
        .collect()
}

fn shader(text: &str) -> &str {
    let start = text.find("::begin shader\n").expect("shader block") + "::begin shader\n".len();
    let end = text.find("::end shader").expect("end of the shader block");
    &text[start..end]
}

fn run(cmd: &mut Command, what: &str) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: {e} (install glslang-tools and g++; .ci/run does)"));
    assert!(
        out.status.success(),
        "{what} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Whether `tool` runs here; with `GONIO_REQUIRE_GLSL_TOOLS` set (CI) a
/// missing one fails the test instead.
fn available(tool: &str) -> bool {
    let found = Command::new(tool).arg("--version").output().is_ok();
    if !found {
        assert!(
            std::env::var_os("GONIO_REQUIRE_GLSL_TOOLS").is_none(),
            "{tool} is required here (GONIO_REQUIRE_GLSL_TOOLS): install glslang-tools and g++"
        );
        eprintln!("{tool} not found: its check of the exported shaders is skipped (install glslang-tools and g++; .ci/run does)");
    }
    found
}

/// Compiles the shader as a GLSL 4.10 fragment shader, parameters as uniforms.
fn check_glsl(dir: &Path, name: &str, text: &str) {
    let mut src = String::from("#version 410 core\n");
    for (p, ..) in parameters(text) {
        let _ = writeln!(src, "uniform float {p};");
    }
    src.push_str(shader(text));
    src.push_str(
        "out vec4 color;\nvoid main()\n{\n    color = vec4(BRDF(vec3(0.0, 0.6, 0.8), vec3(0.0, 0.0, 1.0), \
         vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)), 1.0);\n}\n",
    );
    let path = dir.join(format!("{name}.frag"));
    std::fs::write(&path, src).unwrap();
    run(Command::new("glslangValidator").arg(&path), &format!("glslangValidator {name}"));
}

/// Parses the shader with naga's GLSL front end as a Vulkan-style GLSL 4.50
/// fragment shader (naga's dialect: the parameters in a uniform block, the
/// output at a location) and validates the module.
fn check_naga(name: &str, text: &str) {
    let mut src = String::from("#version 450 core\n");
    let params = parameters(text);
    // An empty uniform block is no GLSL: a rational shader has no parameter.
    if !params.is_empty() {
        src.push_str("layout(set = 0, binding = 0) uniform Parameters {\n");
        for (p, ..) in params {
            let _ = writeln!(src, "    float {p};");
        }
        src.push_str("};\n");
    }
    src.push_str(shader(text));
    src.push_str(
        "layout(location = 0) out vec4 color;\nvoid main()\n{\n    color = vec4(BRDF(vec3(0.0, 0.6, 0.8), vec3(0.0, 0.0, 1.0), \
         vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)), 1.0);\n}\n",
    );
    let options = naga::front::glsl::Options::from(naga::ShaderStage::Fragment);
    let module = naga::front::glsl::Frontend::default()
        .parse(&options, &src)
        .unwrap_or_else(|e| panic!("naga cannot parse {name}:\n{}\n{src}", e.emit_to_string(&src)));
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
        .validate(&module)
        .unwrap_or_else(|e| panic!("naga rejects {name}:\n{}", e.emit_to_string(&src)));
    assert!(
        module.functions.iter().any(|(_, f)| f.name.as_deref() == Some("BRDF")),
        "{name}: no BRDF function"
    );
}

/// A random right-handed orthonormal frame `(N, X, Y)`.
fn frame(rng: &mut impl Rng) -> [[f64; 3]; 3] {
    let unit = |rng: &mut dyn rand::RngCore| loop {
        let v: [f64; 3] = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.1 && n < 1.0 {
            return [v[0] / n, v[1] / n, v[2] / n];
        }
    };
    let n = unit(rng);
    let t = unit(rng);
    let d = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
    let x = [t[0] - d * n[0], t[1] - d * n[1], t[2] - d * n[2]];
    let xl = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    let x = [x[0] / xl, x[1] / xl, x[2] / xl];
    let y = [n[1] * x[2] - n[2] * x[1], n[2] * x[0] - n[0] * x[2], n[0] * x[1] - n[1] * x[0]];
    [n, x, y]
}

fn world(local: [f64; 3], [n, x, y]: [[f64; 3]; 3]) -> [f64; 3] {
    [0, 1, 2].map(|k| local[0] * x[k] + local[1] * y[k] + local[2] * n[k])
}

/// The shader evaluated by C++ (`scalar` float or double) at each geometry.
fn evaluate_as_cpp(dir: &Path, name: &str, text: &str, scalar: &str, geos: &[(f64, f64, f64)]) -> Vec<f64> {
    let mut src = String::from("#include \"shim.hpp\"\n");
    for (p, _, _, v) in parameters(text) {
        let _ = writeln!(src, "float {p} = {v:e};");
    }
    src.push_str(shader(text));
    src.push_str(
        "int main()\n{\n    double w[15];\n    while (true) {\n        for (int k = 0; k < 15; k++)\n            \
         if (scanf(\"%lf\", &w[k]) != 1) return 0;\n        vec3 L(w[0], w[1], w[2]), V(w[3], w[4], w[5]), \
         N(w[6], w[7], w[8]), X(w[9], w[10], w[11]), Y(w[12], w[13], w[14]);\n        \
         printf(\"%.17g\\n\", (double)BRDF(L, V, N, X, Y).x);\n    }\n}\n",
    );
    let cpp = dir.join(format!("{name}-{scalar}.cpp"));
    let exe = dir.join(format!("{name}-{scalar}"));
    std::fs::write(&cpp, src).unwrap();
    let shim = Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
    run(
        Command::new("g++")
            .args([
                "-O1",
                "-std=c++17",
                "-Wall",
                "-Werror",
                "-Wno-unused-function",
                "-Wno-unused-variable",
                "-Wno-unused-but-set-variable",
            ])
            .arg(format!("-DGLSL_FLOAT={scalar}"))
            .arg("-I")
            .arg(&shim)
            .arg(&cpp)
            .arg("-o")
            .arg(&exe),
        &format!("g++ {name} ({scalar})"),
    );
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut input = String::new();
    for &(ti, to, dp) in geos {
        let d = Directions::from_angles(ti, to, dp);
        let f = frame(&mut rng);
        // The light at any azimuth in the surface's frame, not only at 0 as
        // `Directions` puts it: a BRDF of an isotropic surface does not see it.
        let psi: f64 = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
        let turn = |w: [f64; 3]| [w[0] * psi.cos() - w[1] * psi.sin(), w[0] * psi.sin() + w[1] * psi.cos(), w[2]];
        for w in [world(turn(d.l), f), world(turn(d.v), f), f[0], f[1], f[2]] {
            let _ = write!(input, "{:e} {:e} {:e} ", w[0], w[1], w[2]);
        }
        input.push('\n');
    }
    let input_path = dir.join(format!("{name}-{scalar}.in"));
    std::fs::write(&input_path, input).unwrap();
    let out = run(
        Command::new(&exe).stdin(std::fs::File::open(&input_path).unwrap()),
        &format!("{name} ({scalar})"),
    );
    out.lines().map(|l| l.parse().unwrap()).collect()
}

fn geometries() -> Vec<(f64, f64, f64)> {
    let mut g = synthetic::belcour_geometries();
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for _ in 0..1000 {
        g.push((
            rng.random_range(0.0..80f64).to_radians(),
            rng.random_range(0.0..85f64).to_radians(),
            rng.random_range(-180.0..180f64).to_radians(),
        ));
    }
    g
}

/// Every model and retro cosine: the parameter lines carry the fitted values
/// inside the bounds, the GLSL compiles, and the shader is the model: in
/// double precision to 1e-9 (relative to the model's largest value on the
/// grid), in single precision (a GPU) to 1e-3 of it (blinn-retro's lobe
/// exponent of 7 910 turns float's 6e-8 rounding of `n·h` into 3e-4).
#[test]
fn brdf_explorer_shaders_compile_and_equal_the_models() {
    let dir = tempfile::tempdir().unwrap();
    let geos = geometries();
    for model in ModelId::ALL {
        let params: &[Param] = if model.has_retro_cosine() {
            &[Param::View, Param::Back]
        } else {
            &[Param::View]
        };
        for &param in params {
            let m = Material {
                param,
                ..synthetic::reference(model)
            };
            let name = format!("{}-{}", model.name(), if param == Param::View { "view" } else { "back" });
            let text = brdf_explorer::write(&m, &["test".into()]);
            assert!(text.starts_with("analytic\n"));
            let lines = parameters(&text);
            assert_eq!(lines.len(), model.param_names().len());
            for ((p, lo, hi, v), (want_name, want)) in lines.iter().zip(model.param_names().iter().zip(&m.params)) {
                assert_eq!(p, want_name);
                assert_eq!(v, want, "{name}: default of {p}");
                assert!(lo <= v && v <= hi && lo < hi, "{name}: {p} range [{lo}, {hi}] ∌ {v}");
            }
            let want: Vec<f64> = geos
                .iter()
                .map(|&(ti, to, dp)| m.eval(&Directions::from_angles(ti, to, dp)))
                .collect();
            check_shader(dir.path(), &name, &text, &geos, &want, [1e-9, 1e-3]);
        }
    }
}

/// How close a rational shader is to its function (of the peak), in double
/// and single precision. Double is looser than a model's 1e-9: the
/// coordinates' square-root warp (`rational::basis`) takes a rounding ε of
/// the directions at the retro direction to √ε (5e-9 measured there).
const RATIONAL_TOLERANCES: [f64; 2] = [1e-7, 1e-3];

/// A rational function fitted to a material none of the models is (the
/// glass-bead layer, ±0.5 sr⁻¹), in both planes, with and without the
/// cosine factor: the shader is the function,
/// to 1e-9 of its peak in double precision and 1e-3 in single, wherever its
/// denominator is positive.
#[test]
fn rational_shaders_compile_and_equal_the_function() {
    let dir = tempfile::tempdir().unwrap();
    let geos = geometries();
    let beads = GlassBeads::default();
    let data = synthetic::samples_of(|d: &Directions| beads.eval(d), &synthetic::belcour_geometries(), 1_500, 0.02, 7);
    let cases = Parametrization::BOTH
        .map(|p| (p, true))
        .into_iter()
        .chain([(Parametrization::Back, false)]);
    for (parametrization, cosine) in cases {
        let spec = RationalSpec {
            parametrization,
            segments: SegmentSource::Absolute(0.5),
            max_degree: 5,
            cosine,
            densify: None,
        };
        let r = rational::fit(&data, &spec).expect("a rational fit").function;
        let name = format!("rational-{}{}", parametrization.name(), if cosine { "" } else { "-plain" });
        let text = brdf_explorer::write_rational(&r, &["test".into()]);
        assert!(parameters(&text).is_empty(), "{name}: the coefficients are in the shader");
        let want: Vec<f64> = geos
            .iter()
            .map(|&(ti, to, dp)| r.eval(&Directions::from_angles(ti, to, dp)))
            .collect();
        assert!(want.iter().filter(|v| v.is_finite()).count() > geos.len() * 9 / 10, "{name}: poles");
        check_shader(dir.path(), &name, &text, &geos, &want, RATIONAL_TOLERANCES);
    }
}

/// Every coordinate system's shader is its function: a hand-made function
/// of degree 3 whose denominator is positive over the whole box (its
/// constant term outweighs the others), so that the shader's coordinates,
/// not a fit's poles, are what is compared, in each system the fit may
/// choose (`rational::basis::Coordinates`).
#[test]
fn every_coordinate_system_has_its_shader() {
    let dir = tempfile::tempdir().unwrap();
    let geos = geometries();
    let basis = Basis::with_terms(20);
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let numerator: Vec<f64> = (0..basis.len())
        .map(|k| if k == 0 { 2.0 } else { rng.random_range(-0.1..0.1) })
        .collect();
    let denominator: Vec<f64> = (0..basis.len())
        .map(|k| if k == 0 { 1.0 } else { rng.random_range(-0.04..0.04) })
        .collect();
    for coordinates in [Coordinates::Back, Coordinates::LightView, Coordinates::ViewProjected] {
        let points: Vec<[f64; 3]> = geos
            .iter()
            .map(|&(ti, to, dp)| coordinates.of(&Directions::from_angles(ti, to, dp)))
            .collect();
        let r = Rational {
            coordinates,
            degree: basis.degree,
            cosine: true,
            quantity: Units::Fr,
            domain: Domain::around(&points),
            order: basis.order,
            numerator: numerator.clone(),
            denominator: denominator.clone(),
        };
        let name = format!("rational-made-{}", coordinates.name());
        let text = brdf_explorer::write_rational(&r, &["test".into()]);
        let want: Vec<f64> = geos
            .iter()
            .map(|&(ti, to, dp)| r.eval(&Directions::from_angles(ti, to, dp)))
            .collect();
        assert!(want.iter().all(|v| v.is_finite() && *v > 0.0), "{name}: a pole");
        check_shader(dir.path(), &name, &text, &geos, &want, RATIONAL_TOLERANCES);
    }
}

/// naga and glslangValidator accept the shader, and evaluated as C++ it
/// gives `want` at `geos` (NaN where there is no value to compare): to 1e-9
/// of the largest value in double precision, to `float_tol` in single.
fn check_shader(dir: &Path, name: &str, text: &str, geos: &[(f64, f64, f64)], want: &[f64], [double_tol, float_tol]: [f64; 2]) {
    let (glslang, cpp) = (available("glslangValidator"), available("g++"));
    check_naga(name, text);
    if glslang {
        check_glsl(dir, name, text);
    }
    if !cpp {
        return;
    }
    let scale = want.iter().cloned().filter(|v| v.is_finite()).fold(0.0, f64::max);
    assert!(scale > 0.0);
    for (scalar, tol) in [("double", double_tol), ("float", float_tol)] {
        let got = evaluate_as_cpp(dir, name, text, scalar, geos);
        assert_eq!(got.len(), geos.len(), "{name} ({scalar}): one value per geometry");
        let (worst, at) = got
            .iter()
            .zip(want)
            .zip(geos)
            .filter(|((_, w), _)| w.is_finite())
            .map(|((g, w), at)| {
                assert!(
                    g.is_finite(),
                    "{name} ({scalar}): the shader gives {g} where the model gives {w}, at {at:?}"
                );
                ((g - w).abs() / scale, *at)
            })
            .fold((0.0, (0.0, 0.0, 0.0)), |acc, (e, at)| if e > acc.0 { (e, at) } else { acc });
        eprintln!("{name} ({scalar}): max |shader − model| / peak = {worst:.2e}");
        assert!(
            worst <= tol,
            "{name} ({scalar}): |shader − model| = {worst:e} of the peak at θi {:.2}°, θo {:.2}°, Δφ {:.2}°",
            at.0.to_degrees(),
            at.1.to_degrees(),
            at.2.to_degrees()
        );
    }
}

/// naga's check is a check: a shader calling a function nobody defined is refused.
#[test]
fn naga_refuses_a_shader_with_an_undefined_name() {
    let text = brdf_explorer::write(&synthetic::reference(ModelId::ALL[0]), &["test".into()]);
    let broken = text.replacen(
        "::begin shader\n",
        "::begin shader\nfloat broken(float x) { return undefined_function(x); }\n",
        1,
    );
    assert_ne!(broken, text);
    check_naga("lambert", &text);
    let refused = std::panic::catch_unwind(|| check_naga("broken", &broken));
    assert!(refused.is_err(), "naga accepted a call of an undefined function");
}
