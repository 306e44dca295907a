//! A material as a renderer draws it: two scenes of a plane of the material,
//! drawn by Mitsuba 3 from its `.bsdf` file (`assets/render_bsdf.py`, run
//! by `python3` where Mitsuba is installed), and our own integration of the
//! same scenes from the model, to hold the pictures to.
//!
//! The scenes: an orthographic camera 10 units away, 30° from the normal,
//! seeing a square of side 1, and a point light either 0.25 beside the
//! camera (1.4° off its axis: headlights on a sign) or 40° round from it.

use crate::formats::rgl;
use anyhow::{bail, Context, Result};
use gonio_brdf::frame::{cross, dot};
use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;

const SCRIPT: &str = include_str!("../assets/render_bsdf.py");
/// Rays per side of the square our integration averages over.
const RAYS: usize = 256;

/// An orthographic camera over the plane `z = 0`, and a point light.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub name: &'static str,
    /// Camera position; it looks at the origin.
    pub origin: [f64; 3],
    pub up: [f64; 3],
    /// Half the side of the square the camera sees, in its own plane.
    pub half: f64,
    pub light: [f64; 3],
    /// Radiant intensity of the light (W/sr, the same at every wavelength).
    pub intensity: f64,
    /// What the picture shows, in a sentence.
    pub caption: &'static str,
}

fn add(a: [f64; 3], b: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2]]
}

/// The retro scene and the side-lit one.
pub fn scenes() -> [Scene; 2] {
    let (s, c) = 30f64.to_radians().sin_cos();
    let camera = [10.0 * s, 0.0, 10.0 * c];
    let up = [-c, 0.0, s];
    let (s40, c40) = 40f64.to_radians().sin_cos();
    [
        Scene {
            name: "render-retro",
            origin: camera,
            up,
            half: 0.5,
            light: add(camera, [0.0, 1.0, 0.0], 0.25),
            intensity: 100.0,
            caption: "lit by a point light 1.4° off the camera's axis, as headlights light a sign",
        },
        Scene {
            name: "render-side",
            origin: camera,
            up,
            half: 0.5,
            light: [camera[0] * c40, camera[0] * s40, camera[2]],
            intensity: 100.0,
            caption: "lit from 40° round the normal from the camera",
        },
    ]
}

impl Scene {
    /// Our integration of the picture: the radiance `f·cos θl·I/r²` averaged
    /// over the square the camera sees, on a grid of its rays.
    pub fn mean_radiance(&self, brdf: &rgl::Brdf) -> f64 {
        let norm = dot(self.origin, self.origin).sqrt();
        let forward = self.origin.map(|x| -x / norm);
        let right = cross(forward, self.up);
        let view = forward.map(|c| -c);
        let mut sum = 0.0;
        for i in 0..RAYS {
            for j in 0..RAYS {
                let at = |k: usize| (2.0 * (k as f64 + 0.5) / RAYS as f64 - 1.0) * self.half;
                let start = add(add(self.origin, right, at(i)), self.up, at(j));
                let p = add(start, forward, -start[2] / forward[2]);
                let to_light = add(self.light, p, -1.0);
                let r2 = dot(to_light, to_light);
                let l = to_light.map(|c| c / r2.sqrt());
                sum += rgl::fr_cos(brdf, view, l) * self.intensity / r2;
            }
        }
        sum / (RAYS * RAYS) as f64
    }

    fn json(&self) -> Value {
        json!({"name": self.name, "origin": self.origin, "up": self.up, "half": self.half, "light": self.light, "intensity": self.intensity})
    }
}

/// Why the renderer did not draw, from its stderr: the module `python3`
/// lacks, by the name pip installs it under, or Python's last line.
fn not_rendered(stderr: &str) -> String {
    let last = stderr.lines().last().unwrap_or("no message");
    let missing = stderr
        .lines()
        .rev()
        .find_map(|l| l.split("No module named '").nth(1))
        .and_then(|rest| rest.split(['\'', '.']).next());
    match missing {
        Some(module) => {
            let package = match module {
                "mitsuba" | "drjit" => "mitsuba",
                "PIL" => "pillow",
                other => other,
            };
            format!("Mitsuba 3 did not render: python3 has no module `{module}` (pip install {package})")
        }
        None => format!("Mitsuba 3 did not render: {last}"),
    }
}

/// What Mitsuba drew: its version and each picture's mean radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    pub mitsuba: String,
    pub means: Vec<f64>,
}

/// Has Mitsuba 3 render `file` (an RGL `.bsdf`) in `scenes`, writing
/// `NAME.png` per scene into `png_dir` if given. An error says why it could
/// not (no `python3`, no Mitsuba, a file it refuses).
pub fn with_mitsuba(file: &Path, scenes: &[Scene], png_dir: Option<&Path>) -> Result<Rendered> {
    let job = json!({"file": file, "scenes": scenes.iter().map(Scene::json).collect::<Vec<_>>(), "png_dir": png_dir});
    let out = Command::new("python3")
        .args(["-c", SCRIPT])
        .arg(job.to_string())
        .output()
        .context("cannot run python3 (needed, with Mitsuba 3, to render)")?;
    if !out.status.success() {
        bail!("{}", not_rendered(&String::from_utf8_lossy(&out.stderr)));
    }
    let v: Value = serde_json::from_slice(&out.stdout).context("the renderer's answer is not JSON")?;
    let means = v["means"]
        .as_array()
        .context("no means")?
        .iter()
        .filter_map(Value::as_f64)
        .collect::<Vec<_>>();
    if means.len() != scenes.len() {
        bail!("Mitsuba drew {} of {} pictures", means.len(), scenes.len());
    }
    Ok(Rendered {
        mitsuba: v["mitsuba"].as_str().unwrap_or("?").to_string(),
        means,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hint_names_the_module_python_lacks() {
        let numpy =
            "Traceback (most recent call last):\n  File \"<string>\", line 19, in <module>\nModuleNotFoundError: No module named 'numpy'";
        assert_eq!(
            not_rendered(numpy),
            "Mitsuba 3 did not render: python3 has no module `numpy` (pip install numpy)"
        );
        let drjit = "ModuleNotFoundError: No module named 'drjit.llvm'";
        assert!(not_rendered(drjit).ends_with("no module `drjit` (pip install mitsuba)"));
        assert_eq!(
            not_rendered("RuntimeError: bad tensor"),
            "Mitsuba 3 did not render: RuntimeError: bad tensor"
        );
    }

    #[test]
    fn a_lambertian_plane_gives_the_inverse_square_law() {
        // ρ/π · cos θl · I / r², nearly constant over a small square far away.
        let f = |_: &gonio_brdf::Directions| 0.5 / std::f64::consts::PI;
        let side = &scenes()[1];
        let r2 = dot(side.light, side.light);
        let cos = side.light[2] / r2.sqrt();
        let want = 0.5 / std::f64::consts::PI * cos * side.intensity / r2;
        let got = side.mean_radiance(&f);
        assert!((got / want - 1.0).abs() < 0.01, "{got} vs {want}");
    }
}
