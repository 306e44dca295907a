//! `render-check`: the `.bsdf` export read by Mitsuba 3 itself (issue #34).
//! For every model (at the parameters `fit-bench` recovers), the narrow tape
//! the defaults are sized for and the glass-bead material (none of the
//! models), it writes the RGL file, then has `tests/render/mitsuba_check.py`
//! load it with Mitsuba's `measured` plugin (`scalar_spectral`), evaluate it
//! at 2 000 direction pairs and the retro peak, and render a plane lit by a
//! point light beside an orthographic camera (the retro image) and from the
//! side. Each is compared with our own model: the pairs with `f·cos θo`, the
//! images' mean radiance with our integration of the same scene.
//!
//! Bars: median relative error ≤ 2 %, 95th percentile ≤ 10 %, retro peak
//! within 5 %, each image's mean within 5 %. Prints one JSON object; exits
//! non-zero when a bar is missed or Mitsuba cannot be run (`pip install
//! mitsuba==3.9.1`).

use anyhow::{bail, ensure, Context, Result};
use gonio_analysis::formats::rgl::{self, Options, Table};
use gonio_brdf::{Directions, Material, ModelId, Param, Specimen};
use gonio_tests::synthetic::reference;
use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;

const PAIRS: usize = 2000;
const LOBE_DEG: f64 = 3.0;
const IMAGE_TOLERANCE: f64 = 0.05;

/// An orthographic camera over a plane `z = 0` of the material, and a point light.
struct Scene {
    name: &'static str,
    /// Camera position, looking at the origin along `−origin`.
    origin: [f64; 3],
    up: [f64; 3],
    /// Half the side of the square the camera sees, in its own plane.
    half: f64,
    light: [f64; 3],
    /// Radiant intensity of the light (W/sr, flat spectrum).
    intensity: f64,
}

fn add(a: [f64; 3], b: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2]]
}

fn scenes() -> [Scene; 2] {
    let view = |deg: f64, dist: f64| {
        let t = deg.to_radians();
        [dist * t.sin(), 0.0, dist * t.cos()]
    };
    let camera = view(30.0, 10.0);
    let up = [-30f64.to_radians().cos(), 0.0, 30f64.to_radians().sin()];
    [
        // Headlights: the light 0.25 from the camera at 10, 1.4° off its axis.
        Scene {
            name: "retro",
            origin: camera,
            up,
            half: 0.5,
            light: add(camera, [0.0, 1.0, 0.0], 0.25),
            intensity: 100.0,
        },
        // The light 40° round from the camera.
        Scene {
            name: "side",
            origin: camera,
            up,
            half: 0.5,
            light: {
                let (s, c) = 40f64.to_radians().sin_cos();
                [camera[0] * c, camera[0] * s, camera[2]]
            },
            intensity: 100.0,
        },
    ]
}

impl Scene {
    /// Our integration of the image: the radiance `f·cos θl·I/r²` averaged
    /// over the square the camera sees, on a 256² grid of its rays.
    fn mean_radiance(&self, brdf: &dyn Fn(&Directions) -> f64) -> f64 {
        let norm = gonio_brdf::frame::dot(self.origin, self.origin).sqrt();
        let forward = self.origin.map(|x| -x / norm);
        let right = gonio_brdf::frame::cross(forward, self.up);
        let n = 256;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (
                    (2.0 * (i as f64 + 0.5) / n as f64 - 1.0) * self.half,
                    (2.0 * (j as f64 + 0.5) / n as f64 - 1.0) * self.half,
                );
                let start = add(add(self.origin, right, x), self.up, y);
                let p = add(start, forward, -start[2] / forward[2]);
                let to_light = add(self.light, p, -1.0);
                let r2 = gonio_brdf::frame::dot(to_light, to_light);
                let l = to_light.map(|c| c / r2.sqrt());
                let v = forward.map(|c| -c);
                sum += rgl::fr_cos(brdf, v, l) * self.intensity / r2;
            }
        }
        sum / (n * n) as f64
    }

    fn json(&self) -> Value {
        json!({"name": self.name, "origin": self.origin, "up": self.up, "half": self.half, "light": self.light, "intensity": self.intensity})
    }
}

fn materials() -> Vec<(String, Specimen)> {
    let mut out: Vec<(String, Specimen)> = ModelId::ALL
        .iter()
        .map(|&m| (m.name().to_string(), Specimen::Model(reference(m))))
        .collect();
    let narrow = Material {
        model: ModelId::RetroPhong,
        params: vec![0.05, 1000.0, 0.8, 0.1, 0.02, 3.0],
        param: Param::View,
    };
    out.push(("narrow-tape".into(), Specimen::Model(narrow)));
    out.push(("glass-beads".into(), Specimen::default()));
    out
}

fn main() {
    match run() {
        Ok(ok) => std::process::exit(if ok { 0 } else { 1 }),
        Err(e) => {
            println!("{}", json!({"error": format!("{e:#}")}));
            std::process::exit(2);
        }
    }
}

fn run() -> Result<bool> {
    let dir = tempfile::tempdir()?;
    let drawn = rgl::pairs(PAIRS, LOBE_DEG.to_radians(), 2026);
    let retro = rgl::retro_directions();
    let scenes = scenes();
    let mut cases = Vec::new();
    for (name, specimen) in materials() {
        let eval = |d: &Directions| specimen.eval(d);
        let table = Table::new(&eval, &format!("render-check: {name}"), &Options::default())?;
        let file = dir.path().join(format!("{name}.bsdf"));
        std::fs::write(&file, table.bytes())?;
        cases.push(json!({
            "name": name,
            "file": file,
            "pairs": drawn,
            "ours": drawn.iter().map(|&(wi, wo)| rgl::fr_cos(&eval, wi, wo)).collect::<Vec<_>>(),
            "retro": retro,
            "ours_retro": retro.iter().map(|&w| rgl::fr_cos(&eval, w, w)).collect::<Vec<_>>(),
            "images": scenes.iter().map(|s| s.mean_radiance(&eval)).collect::<Vec<_>>(),
        }));
    }
    let input = dir.path().join("cases.json");
    std::fs::write(
        &input,
        serde_json::to_vec(&json!({"scenes": scenes.iter().map(Scene::json).collect::<Vec<_>>(), "cases": cases}))?,
    )?;
    let output = dir.path().join("mitsuba.json");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("render/mitsuba_check.py");
    let status = Command::new("python3")
        .arg(&script)
        .arg(&input)
        .arg(&output)
        .status()
        .context("cannot run python3")?;
    ensure!(
        status.success(),
        "{} failed ({status}): is Mitsuba 3 installed (pip install mitsuba==3.9.1)?",
        script.display()
    );
    let got: Value = serde_json::from_slice(&std::fs::read(&output)?)?;
    compare(&cases, &got)
}

fn compare(cases: &[Value], got: &Value) -> Result<bool> {
    let [median_bar, p95_bar, peak_bar] = rgl::TOLERANCE;
    let mut rows = Vec::new();
    let mut all_ok = true;
    for case in cases {
        let name = case["name"].as_str().unwrap_or_default();
        let g = &got["cases"][name];
        let floats = |v: &Value| -> Result<Vec<f64>> {
            v.as_array()
                .context("not an array")?
                .iter()
                .map(|x| x.as_f64().context("not a number"))
                .collect()
        };
        let (evals, retro, images) = (floats(&g["pairs"])?, floats(&g["retro"])?, floats(&g["images"])?);
        let errors = rgl::relative_errors(evals.iter().copied(), floats(&case["ours"])?.into_iter());
        let peak = rgl::relative_errors(retro.iter().copied(), floats(&case["ours_retro"])?.into_iter());
        let peak = peak.last().copied().unwrap_or(f64::NAN);
        let ours = floats(&case["images"])?;
        if ours.len() != images.len() || evals.len() != PAIRS {
            bail!("{name}: Mitsuba gave {} values and {} images", evals.len(), images.len());
        }
        let image_errors: Vec<f64> = images.iter().zip(&ours).map(|(m, o)| (m - o).abs() / o).collect();
        let (median, p95) = (rgl::quantile(&errors, 0.5), rgl::quantile(&errors, 0.95));
        let ok = median <= median_bar && p95 <= p95_bar && peak <= peak_bar && image_errors.iter().all(|&e| e <= IMAGE_TOLERANCE);
        all_ok &= ok;
        eprintln!(
            "{name:<20} median {:6.3} %  p95 {:6.3} %  retro peak {:6.3} %  images {}  {}",
            100.0 * median,
            100.0 * p95,
            100.0 * peak,
            images
                .iter()
                .zip(&ours)
                .map(|(m, o)| format!("{m:.4} vs {o:.4}"))
                .collect::<Vec<_>>()
                .join(", "),
            if ok { "ok" } else { "MISSED" }
        );
        rows.push(json!({"material": name, "pairs": errors.len(), "median": median, "p95": p95, "retro_peak": peak,
                         "images": scenes().iter().zip(images.iter().zip(&ours)).map(|(s, (m, o))| json!({"scene": s.name, "mitsuba": m, "ours": o, "error": (m - o).abs() / o})).collect::<Vec<_>>(),
                         "ok": ok}));
    }
    println!(
        "{}",
        json!({"mitsuba": got["version"], "variant": got["variant"], "bars": {"median": median_bar, "p95": p95_bar, "retro_peak": peak_bar, "image": IMAGE_TOLERANCE},
               "materials": rows, "all_within_bars": all_ok})
    );
    Ok(all_ok)
}
