//! The solid angle each sample stands for, among the samples of its
//! incidence: what makes a fit of two scans that sample the hemisphere
//! differently (a grid's even steps, a sweep scan's rows crowding around the
//! retro direction) fit the same thing, `∫ (f − model)² dΩ`, rather than
//! whatever their densities favour. A model outside the material's family
//! otherwise settles where the samples crowd.

use super::data::Observation;
use std::f64::consts::{FRAC_PI_2, PI};

/// Side of the cells the hemisphere is divided into (rad): well below the
/// spacing of any scan's samples away from the retro direction.
const CELL: f64 = 0.25 * PI / 180.0;

/// Incidences closer than this (rad) are one incidence.
const SAME_INCIDENCE: f64 = 0.05 * PI / 180.0;

/// The solid angle (sr) each observation stands for: its cell of the
/// spherical Voronoi diagram of the view directions at its incidence, the
/// directions nearer to it than to any other sample, short of the retro
/// direction where no sample lies. Measured by dividing
/// the hemisphere into cells of about [`CELL`] a side and giving each cell's
/// solid angle to the sample nearest its centre: exact in the limit, with
/// no assumption on how the samples lie (a density from the k nearest
/// neighbours would count a sweep scan's rows, 1° apart along a row and up
/// to 10° across, as dense as they are along the row, and the fit would
/// move with k). Brute force: each cell (330 000 over the
/// hemisphere) against each sample of its incidence, some 10⁹ dot products
/// for a sweep scan's 10 000 samples at three incidences, a second or two.
/// Cells much smaller than the samples' spacing are what make it exact: a
/// sweep slower than some 7 deg/s spaces its samples closer than a cell
/// along the row, and the cells quantise their weights.
pub fn solid_angles(obs: &[Observation]) -> Vec<f64> {
    let view = |o: &Observation| {
        let (st, ct) = o.theta_o.sin_cos();
        let (sp, cp) = o.dphi.sin_cos();
        [st * cp, st * sp, ct]
    };
    let cells = cells();
    let mut order: Vec<usize> = (0..obs.len()).collect();
    order.sort_by(|&a, &b| obs[a].theta_i.total_cmp(&obs[b].theta_i));
    let mut area = vec![0.0; obs.len()];
    let mut start = 0;
    while start < order.len() {
        let ti = obs[order[start]].theta_i;
        let end = order[start..]
            .iter()
            .position(|&k| (obs[k].theta_i - ti).abs() > SAME_INCIDENCE)
            .map_or(order.len(), |p| start + p);
        let group = &order[start..end];
        // Structure of arrays: the inner loop vectorises.
        let dirs: Vec<[f64; 3]> = group.iter().map(|&k| view(&obs[k])).collect();
        let (x, y, z): (Vec<f64>, Vec<f64>, Vec<f64>) = (
            dirs.iter().map(|d| d[0]).collect(),
            dirs.iter().map(|d| d[1]).collect(),
            dirs.iter().map(|d| d[2]).collect(),
        );
        // Cells nearer the retro direction than every sample lie in the
        // head's blind zone around it: no scan samples them, and they stand
        // for nothing (given to the samples at its edge, they would weigh
        // whichever scan's samples lie nearest it).
        let (sl, cl) = ti.sin_cos();
        let retro = |d: &[f64; 3]| d[0] * sl + d[2] * cl;
        let edge = dirs.iter().map(retro).fold(f64::NEG_INFINITY, f64::max);
        for (c, omega) in cells.iter().filter(|(c, _)| retro(c) <= edge) {
            let mut best = (f64::NEG_INFINITY, 0);
            for j in 0..x.len() {
                let dot = c[0] * x[j] + c[1] * y[j] + c[2] * z[j];
                if dot > best.0 {
                    best = (dot, j);
                }
            }
            area[group[best.1]] += omega;
        }
        start = end;
    }
    area
}

/// The hemisphere in cells of about [`CELL`] a side: rings of polar angle,
/// each cut into as many azimuth steps as keep the cells square; each cell's
/// centre direction and its exact solid angle (they sum to 2π).
fn cells() -> Vec<([f64; 3], f64)> {
    let rings = (FRAC_PI_2 / CELL).round() as usize;
    let dt = FRAC_PI_2 / rings as f64;
    let mut out = Vec::new();
    for r in 0..rings {
        let (t0, t1) = (r as f64 * dt, (r + 1) as f64 * dt);
        let t = 0.5 * (t0 + t1);
        let steps = ((2.0 * PI * t.sin() / dt).round() as usize).max(1);
        let omega = 2.0 * PI * (t0.cos() - t1.cos()) / steps as f64;
        let (st, ct) = t.sin_cos();
        for s in 0..steps {
            let p = (s as f64 + 0.5) * 2.0 * PI / steps as f64;
            out.push(([st * p.cos(), st * p.sin(), ct], omega));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(theta_i: f64, theta_o: f64, dphi: f64) -> Observation {
        Observation {
            theta_i,
            theta_o,
            dphi,
            value: 1.0,
            sigma: None,
            shared: Default::default(),
        }
    }

    /// An even grid and a grid twice as dense in one half: each half of the
    /// dense one stands for the same solid angle as in the even one, and
    /// either sums to the hemisphere's 2π (but for the cells nearer the
    /// retro direction than any sample).
    #[test]
    fn samples_stand_for_the_solid_angle_they_cover_however_dense() {
        let grid = |dense_half: bool| {
            let mut v = Vec::new();
            for a in 0..24 {
                let phi = (a as f64 * 15.0 - 172.5).to_radians();
                let rows = if dense_half && phi > 0.0 { 2 } else { 1 };
                for r in 0..(10 * rows) {
                    let t = ((r as f64 + 0.5) * 9.0 / rows as f64).to_radians();
                    v.push(at(0.5, t, phi));
                }
            }
            v
        };
        let (even, dense) = (grid(false), grid(true));
        let sum = |o: &[Observation], w: &[f64], half: bool| -> f64 {
            o.iter().zip(w).filter(|(o, _)| (o.dphi > 0.0) == half).map(|(_, w)| w).sum()
        };
        let (we, wd) = (solid_angles(&even), solid_angles(&dense));
        for half in [false, true] {
            let (a, b) = (sum(&even, &we, half), sum(&dense, &wd, half));
            assert!((a / b - 1.0).abs() < 0.1, "half {half}: {a} sr vs {b} sr");
        }
        let total = sum(&even, &we, false) + sum(&even, &we, true);
        assert!((total / (2.0 * PI) - 1.0).abs() < 1e-2, "{total} sr");
    }
}
