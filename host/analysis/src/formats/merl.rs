//! MERL's `.binary` BRDF table (Matusik et al. 2003, the MERL database; its
//! reader `BRDFRead.cpp`): three little-endian `i32` dimensions (90, 90,
//! 180), then `90·90·180` doubles per channel, red, green and blue, each
//! stored as `f_r / scale` with MERL's scales (1/1500, 1.15/1500,
//! 1.66/1500). The table is indexed in Rusinkiewicz's half-difference
//! angles: `θh` on a square-root scale (`index = ⌊√(θh/90°)·90⌋`), `θd` in
//! 1° steps, `φd` in 1° steps over `[0°, 180°)`.
//!
//! What the format assumes: isotropy (no `φh`) and reciprocity (`φd` and
//! `φd + 180°` share a cell). What it resolves of a retroreflector: the
//! retro direction is `θd = 0` and the angle between light and view is
//! `2θd`, so a cell spans 2° of that angle: a lobe of a few degrees (the
//! head's glass beads, a tape's `cos^1000`) is held by one or two cells.
//! Values are taken at the cells' centres; the reader here looks a
//! geometry up the way MERL's does (the cell it falls in, no interpolation).

use anyhow::{bail, ensure, Result};
use gonio_brdf::frame::{dot, normalize};
use gonio_brdf::Directions;
use std::f64::consts::{FRAC_PI_2, PI};

pub const THETA_H: usize = 90;
pub const THETA_D: usize = 90;
pub const PHI_D: usize = 180;
const CELLS: usize = THETA_H * THETA_D * PHI_D;
/// `f_r = stored · scale`, per channel.
pub const SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// A MERL table: `f_r` (sr⁻¹) per channel and cell.
#[derive(Debug, Clone)]
pub struct Merl {
    values: [Vec<f64>; 3],
}

fn rotate(v: [f64; 3], axis: [f64; 3], angle: f64) -> [f64; 3] {
    let (s, c) = angle.sin_cos();
    let k = dot(axis, v) * (1.0 - c);
    let x = gonio_brdf::frame::cross(axis, v);
    std::array::from_fn(|i| v[i] * c + axis[i] * k + x[i] * s)
}

const Z: [f64; 3] = [0.0, 0.0, 1.0];
const Y: [f64; 3] = [0.0, 1.0, 0.0];

/// `(θh, θd, φd)` of a light `l` and a view `v` (MERL's `std_coords_to_half_diff_coords`, light in).
pub fn half_diff(l: [f64; 3], v: [f64; 3]) -> (f64, f64, f64) {
    let h = normalize([l[0] + v[0], l[1] + v[1], l[2] + v[2]]);
    let (theta_h, phi_h) = (h[2].clamp(-1.0, 1.0).acos(), h[1].atan2(h[0]));
    let d = rotate(rotate(l, Z, -phi_h), Y, -theta_h);
    (theta_h, d[2].clamp(-1.0, 1.0).acos(), d[1].atan2(d[0]))
}

/// Light and view at half-difference angles (with `φh = 0`).
fn from_half_diff(theta_h: f64, theta_d: f64, phi_d: f64) -> Directions {
    let d = [theta_d.sin() * phi_d.cos(), theta_d.sin() * phi_d.sin(), theta_d.cos()];
    let mirrored = [-d[0], -d[1], d[2]];
    Directions {
        l: rotate(d, Y, theta_h),
        v: rotate(mirrored, Y, theta_h),
    }
}

/// The cell a geometry falls in, as MERL's reader finds it.
fn cell(theta_h: f64, theta_d: f64, phi_d: f64) -> usize {
    let ih = ((theta_h / FRAC_PI_2).max(0.0).sqrt() * THETA_H as f64) as usize;
    let id = (theta_d / FRAC_PI_2 * THETA_D as f64) as usize;
    let phi = if phi_d < 0.0 { phi_d + PI } else { phi_d };
    let ip = (phi / PI * PHI_D as f64) as usize;
    (ip.min(PHI_D - 1)) + PHI_D * (id.min(THETA_D - 1) + THETA_D * ih.min(THETA_H - 1))
}

impl Merl {
    /// Tabulates a grey `brdf` at every cell's centre. A light or view below
    /// the horizon there gives 0 (MERL's measurements have none). A value
    /// that is NaN, infinite or negative is an error naming its geometry.
    pub fn tabulate(brdf: &dyn Fn(&Directions) -> f64) -> Result<Merl> {
        let mut grey = vec![0.0; CELLS];
        for ih in 0..THETA_H {
            let u = (ih as f64 + 0.5) / THETA_H as f64;
            let theta_h = u * u * FRAC_PI_2;
            for id in 0..THETA_D {
                let theta_d = (id as f64 + 0.5) / THETA_D as f64 * FRAC_PI_2;
                for ip in 0..PHI_D {
                    let phi_d = (ip as f64 + 0.5) / PHI_D as f64 * PI;
                    let d = from_half_diff(theta_h, theta_d, phi_d);
                    if d.l[2] <= 0.0 || d.v[2] <= 0.0 {
                        continue;
                    }
                    let f = brdf(&d);
                    if !(f.is_finite() && f >= 0.0) {
                        bail!(
                            "cannot tabulate: f = {f} at θh = {:.2}°, θd = {:.2}°, φd = {:.2}°",
                            theta_h.to_degrees(),
                            theta_d.to_degrees(),
                            phi_d.to_degrees()
                        );
                    }
                    grey[cell(theta_h, theta_d, phi_d)] = f;
                }
            }
        }
        Ok(Merl {
            values: [grey.clone(), grey.clone(), grey],
        })
    }

    /// `f_r` per channel for a light `l` and a view `v`, from the cell they fall in.
    pub fn lookup(&self, l: [f64; 3], v: [f64; 3]) -> [f64; 3] {
        let (th, td, pd) = half_diff(l, v);
        let c = cell(th, td, pd);
        std::array::from_fn(|k| self.values[k][c])
    }

    /// The file's bytes.
    pub fn bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(12 + 3 * CELLS * 8);
        for n in [THETA_H, THETA_D, PHI_D] {
            out.extend_from_slice(&(n as i32).to_le_bytes());
        }
        for (channel, scale) in self.values.iter().zip(SCALE) {
            for &f in channel {
                out.extend_from_slice(&(f / scale).to_le_bytes());
            }
        }
        out
    }

    /// Reads a file as MERL's reader does: the dimensions must be 90, 90, 180.
    pub fn read(bytes: &[u8]) -> Result<Merl> {
        ensure!(bytes.len() >= 12, "not a MERL table: {} bytes", bytes.len());
        let dims: Vec<i32> = bytes[..12]
            .chunks_exact(4)
            .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        ensure!(
            dims == [THETA_H as i32, THETA_D as i32, PHI_D as i32],
            "MERL dimensions {dims:?}, not [90, 90, 180]"
        );
        ensure!(
            bytes.len() == 12 + 3 * CELLS * 8,
            "MERL table of {} bytes, not {}",
            bytes.len(),
            12 + 3 * CELLS * 8
        );
        let doubles: Vec<f64> = bytes[12..]
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        let channel = |k: usize| doubles[k * CELLS..(k + 1) * CELLS].iter().map(|&x| x * SCALE[k]).collect();
        Ok(Merl {
            values: [channel(0), channel(1), channel(2)],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_brdf::{GlassBeads, Material, ModelId, Param};

    #[test]
    fn half_difference_angles_go_both_ways() {
        for &(th, td, pd) in &[(0.3, 0.2, 0.5), (1.0, 0.7, -2.0), (0.05, 1.2, 3.0)] {
            let d = from_half_diff(th, td, pd);
            let (a, b, c) = half_diff(d.l, d.v);
            assert!(
                (a - th).abs() < 1e-12 && (b - td).abs() < 1e-12 && (c - pd).abs() < 1e-12,
                "{th} {td} {pd} → {a} {b} {c}"
            );
        }
        // Retroreflection is θd = 0, the mirror θh = 0.
        let retro = Directions::from_degrees(40.0, 40.0, 0.0);
        assert!(half_diff(retro.l, retro.v).1 < 1e-7);
        let mirror = Directions::from_degrees(40.0, 40.0, 180.0);
        assert!(half_diff(mirror.l, mirror.v).0 < 1e-7);
    }

    #[test]
    fn a_table_written_reads_back_with_the_values_at_its_cells() {
        let tape = Material {
            model: ModelId::RetroPhong,
            params: vec![0.05, 500.0, 0.8, 0.1, 0.02, 3.0],
            param: Param::View,
        };
        let f = |d: &Directions| tape.eval(d);
        let merl = Merl::tabulate(&f).unwrap();
        let bytes = merl.bytes();
        assert_eq!(bytes.len(), 12 + 3 * 90 * 90 * 180 * 8);
        let back = Merl::read(&bytes).unwrap();
        for &(th, td, pd) in &[(30.5f64, 10.5f64, 20.5f64), (5.0, 0.5, 90.5), (40.0, 20.5, 170.5)] {
            // A cell's centre: the reader gives the model's value there, in every channel.
            let (ih, id, ip) = (((th / 90.0).sqrt() * 90.0).floor(), td.floor(), pd.floor());
            let centre = from_half_diff(
                ((ih + 0.5) / 90.0).powi(2) * FRAC_PI_2,
                (id + 0.5).to_radians(),
                (ip + 0.5).to_radians(),
            );
            assert!(centre.l[2] > 0.0 && centre.v[2] > 0.0);
            let got = back.lookup(centre.l, centre.v);
            for g in got {
                assert!((g / f(&centre) - 1.0).abs() < 1e-12, "{g} vs {}", f(&centre));
            }
        }
        // The same cells read from the bytes with BRDFRead.cpp's own
        // arithmetic: offset 12 + 8·(φd + 180·θd + 180·90·θh) per channel
        // block, times the channel's scale.
        for &(l, v) in &[
            (
                Directions::from_degrees(30.0, 20.0, 40.0).l,
                Directions::from_degrees(30.0, 20.0, 40.0).v,
            ),
            (
                Directions::from_degrees(60.0, 59.0, 1.0).l,
                Directions::from_degrees(60.0, 59.0, 1.0).v,
            ),
        ] {
            let (th, td, pd) = half_diff(l, v);
            let ih = (th / FRAC_PI_2 * 90.0 * 90.0).sqrt() as usize;
            let id = (td / FRAC_PI_2 * 90.0) as usize;
            let ip = ((if pd < 0.0 { pd + PI } else { pd }) / PI * 180.0) as usize;
            let ind = ip + id * 180 + ih * 180 * 90;
            for (k, scale) in SCALE.iter().enumerate() {
                let at = 12 + 8 * (k * 90 * 90 * 180 + ind);
                let raw = f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
                assert!((raw * scale - back.lookup(l, v)[k]).abs() < 1e-12);
                assert!(raw * scale > 0.0);
            }
        }
        let mut wrong = bytes.clone();
        wrong[0] = 91;
        assert!(Merl::read(&wrong).is_err());
        assert!(Merl::read(&bytes[..1000]).is_err());
    }

    #[test]
    fn the_retro_return_falls_in_the_first_theta_d_cells() {
        let beads = GlassBeads::default();
        let f = |d: &Directions| beads.eval(d);
        let merl = Merl::tabulate(&f).unwrap();
        let at = |gamma: f64| {
            merl.lookup(
                Directions::from_degrees(30.0, 30.0 - gamma, 0.0).l,
                Directions::from_degrees(30.0, 30.0 - gamma, 0.0).v,
            )[0]
        };
        // The 0.6° ring is inside the first cell (2θd < 2°): it reads as one value there.
        assert_eq!(at(0.3), at(1.5));
        assert!(at(0.3) > 3.0 * at(6.0));
    }

    #[test]
    fn values_that_are_not_a_brdf_are_refused() {
        let e = Merl::tabulate(&|d: &Directions| if d.cos_i() < 0.2 { f64::NAN } else { 1.0 })
            .unwrap_err()
            .to_string();
        assert!(e.contains("NaN") && e.contains("θd"), "{e}");
    }
}
