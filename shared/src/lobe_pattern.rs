//! The lobe patterns of a scan: rings of points about the retro direction
//! (the laser) and about the mirror direction of each incidence, measured
//! besides the grid, as the CEA head of Belcour et al. 2014 (§2.A) measures
//! the through-splitter zone on rings of observation angle α about the
//! laser and the mirror direction more densely than its grid. A grid 3° ×
//! 10° apart has one point within 3° of the laser, where a retroreflector's
//! lobe falls from its peak to a fifth of it.
//!
//! A ring of radius `α` about a direction `a` holds `azimuths` views `v`
//! at angle `α` from it, evenly around it: `v = cos α·a + sin α·(cos ε·e₁ +
//! sin ε·e₂)`, `e₁` in the plane of incidence towards the horizon, `e₂` across
//! it (ε = 0°: θo = θi + α in the plane of incidence; 90°: beside it). The
//! arm sees the retro rings at `|ψ| = α`: within the head's through-splitter
//! zone they are seen through the splitter (`docs/optics.md`).

use crate::geometry::Geometry;
use libm::{acos, atan2, cos, sin};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

const DEG: f64 = core::f64::consts::PI / 180.0;

/// Rings a pattern holds at most (a scan request stays inside one frame):
/// the reference retro rings and a standard's observation angle besides
/// them (EN 1436's 1.05°, `gonio scan --for`).
pub const RINGS_MAX: usize = 12;
/// Largest ring radius (degrees): a pattern is about a lobe, not the hemisphere.
pub const RADIUS_MAX_DEG: f32 = 30.0;
/// Most views on one ring.
pub const AZIMUTHS_MAX: u16 = 360;

/// Rings about one direction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rings {
    /// Their radii (degrees), each in (0, [`RADIUS_MAX_DEG`]].
    pub radii_deg: heapless::Vec<f32, RINGS_MAX>,
    /// Views on each ring, evenly spaced in azimuth about the direction.
    pub azimuths: u16,
}

/// The patterns each incidence of a scan gets besides its grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LobePatterns {
    /// About the retro direction, the laser (observation angles α).
    pub retro: Rings,
    /// About the mirror direction of the incidence.
    pub mirror: Rings,
}

/// Which direction a ring is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum About {
    Retro,
    Mirror,
}

/// One view of a pattern: on which ring, where on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RingPoint {
    pub about: About,
    pub radius_deg: f32,
    pub azimuth_deg: f32,
}

impl Rings {
    /// No rings.
    pub const fn none() -> Self {
        Rings {
            radii_deg: heapless::Vec::new(),
            azimuths: 0,
        }
    }

    fn from_radii(radii: &[f32], azimuths: u16) -> Self {
        let mut radii_deg = heapless::Vec::new();
        for r in radii.iter().take(RINGS_MAX) {
            // At most RINGS_MAX taken.
            let _ = radii_deg.push(*r);
        }
        Rings { radii_deg, azimuths }
    }

    /// Number of views, or `None` when a radius or the azimuth count is
    /// out of range (no rings at all is 0 views, whatever the count).
    pub fn count(&self) -> Option<u32> {
        if self.radii_deg.is_empty() {
            return Some(0);
        }
        let radii_ok = self.radii_deg.iter().all(|r| r.is_finite() && *r > 0.0 && *r <= RADIUS_MAX_DEG);
        if !radii_ok || self.azimuths == 0 || self.azimuths > AZIMUTHS_MAX {
            return None;
        }
        Some(self.radii_deg.len() as u32 * self.azimuths as u32)
    }

    /// The ring-major index of the `k`-th view visited: azimuth by
    /// azimuth, the rings of each in turn, outward at one azimuth and back
    /// inward at the next. Around a ring the sample turns its normal a whole
    /// turn about the direction, so ring by ring would take that turn once a
    /// ring; this takes it once.
    fn visited(&self, k: u32) -> u32 {
        let n = self.radii_deg.len().max(1) as u32;
        let (azimuth, step) = (k / n, k % n);
        let ring = if azimuth % 2 == 0 { step } else { n - 1 - step };
        ring * self.azimuths as u32 + azimuth
    }

    fn at(&self, about: About, k: u32) -> RingPoint {
        let n = self.azimuths.max(1) as u32;
        RingPoint {
            about,
            radius_deg: self.radii_deg[(k / n) as usize],
            azimuth_deg: 360.0 * (k % n) as f32 / n as f32,
        }
    }
}

impl LobePatterns {
    /// The reference patterns, after the CEA head's: 10 retro rings of α
    /// from 0.1° to 4.75° with 32 views each (320 an incidence; the CEA's
    /// held some 65 on each of 5 rings from 1° to 5°). Seven rings are the
    /// observation angles of ASTM E810 (0.1, 0.2, 0.33, 0.5, 1, 1.5, 2°), and
    /// an even count of views puts two of each ring in the plane of
    /// incidence: an R_A in the coplanar geometry at a measured incidence is
    /// then a measured sample, not an interpolation. The outermost ring lies
    /// a quarter degree inside the reference head's 5° zone, so that an
    /// arm's microstep (0.0025°), its zero (0.02°) and the f32 rounding of ψ
    /// cannot put a view on the plate's shadow. About the mirror direction, 5
    /// rings to 6° with 16 views each: the grid's 3° × 10° is coarse across a
    /// glossy lobe.
    pub fn cea() -> Self {
        LobePatterns {
            retro: Rings::from_radii(&[0.1, 0.2, 0.33, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 4.75], 32),
            mirror: Rings::from_radii(&[1.0, 2.0, 3.0, 4.5, 6.0], 16),
        }
    }

    /// Views of one incidence, or `None` for a malformed pattern.
    pub fn count(&self) -> Option<u32> {
        Some(self.retro.count()? + self.mirror.count()?)
    }

    /// The `k`-th view of an incidence's pattern: the retro rings' first,
    /// ring by ring from the innermost as given, then the mirror's.
    pub fn ring_point(&self, k: u32) -> Option<RingPoint> {
        let retro = self.retro.count()?;
        if k < retro {
            return Some(self.retro.at(About::Retro, k));
        }
        let k = k - retro;
        (k < self.mirror.count()?).then(|| self.mirror.at(About::Mirror, k))
    }

    /// The index ([`LobePatterns::ring_point`]'s) of the `k`-th view
    /// visited: the retro rings' views first, azimuth by azimuth, then the
    /// mirror rings' alike.
    pub fn visited(&self, k: u32) -> Option<u32> {
        let retro = self.retro.count()?;
        if k < retro {
            return Some(self.retro.visited(k));
        }
        let k = k - retro;
        (k < self.mirror.count()?).then(|| retro + self.mirror.visited(k))
    }

    /// The geometry of the `k`-th view at incidence `theta_i_deg`.
    pub fn point(&self, theta_i_deg: f32, k: u32) -> Option<Geometry> {
        self.ring_point(k).map(|p| p.geometry(theta_i_deg))
    }
}

impl RingPoint {
    /// The isotropic geometry of this view at incidence `theta_i_deg`
    /// (θo ≥ 90° where the ring reaches past the horizon: unreachable).
    pub fn geometry(&self, theta_i_deg: f32) -> Geometry {
        let ti = theta_i_deg as f64 * DEG;
        let (si, ci) = (sin(ti), cos(ti));
        // The axis and the unit vector towards the horizon beside it.
        let (axis, e1) = match self.about {
            About::Retro => ([si, 0.0, ci], [ci, 0.0, -si]),
            About::Mirror => ([-si, 0.0, ci], [-ci, 0.0, -si]),
        };
        let (a, e) = (self.radius_deg as f64 * DEG, self.azimuth_deg as f64 * DEG);
        let (ca, sa, ce, se) = (cos(a), sin(a), cos(e), sin(e));
        let v = [ca * axis[0] + sa * ce * e1[0], sa * se, ca * axis[2] + sa * ce * e1[2]];
        let theta_o = acos(v[2].clamp(-1.0, 1.0));
        let dphi = if v[0] == 0.0 && v[1] == 0.0 { 0.0 } else { atan2(v[1], v[0]) };
        Geometry::new(theta_i_deg, (theta_o / DEG) as f32, (dphi / DEG) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(theta_deg: f32, phi_deg: f32) -> [f64; 3] {
        let (t, p) = (theta_deg as f64 * DEG, phi_deg as f64 * DEG);
        [sin(t) * cos(p), sin(t) * sin(p), cos(t)]
    }

    fn angle_deg(a: [f64; 3], b: [f64; 3]) -> f64 {
        acos((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]).clamp(-1.0, 1.0)) / DEG
    }

    /// Every view lies at its ring's radius from its axis, and a ring's
    /// views are evenly spaced around it (each next one as far from the last).
    #[test]
    fn views_lie_on_their_rings_evenly() {
        let p = LobePatterns::cea();
        for ti in [5.0f32, 15.0, 30.0, 60.0] {
            let (l, m) = (unit(ti, 0.0), unit(ti, 180.0));
            let n = p.count().unwrap();
            let mut prev: Option<([f64; 3], RingPoint)> = None;
            for k in 0..n {
                let rp = p.ring_point(k).unwrap();
                let g = rp.geometry(ti);
                let v = unit(g.theta_o_deg, g.dphi_deg);
                let axis = if rp.about == About::Retro { l } else { m };
                assert!((angle_deg(v, axis) - rp.radius_deg as f64).abs() < 2e-4, "θi {ti} {rp:?} {g:?}");
                if let Some((pv, prp)) = prev {
                    if prp.radius_deg == rp.radius_deg && prp.about == rp.about {
                        let az = match rp.about {
                            About::Retro => p.retro.azimuths,
                            About::Mirror => p.mirror.azimuths,
                        };
                        let chord = 2.0 * (sin(rp.radius_deg as f64 * DEG) * sin(core::f64::consts::PI / az as f64)).asin() / DEG;
                        assert!((angle_deg(v, pv) - chord).abs() < 2e-4, "θi {ti} {rp:?}");
                    }
                }
                prev = Some((v, rp));
            }
        }
    }

    #[test]
    fn azimuth_zero_is_in_the_plane_of_incidence_towards_the_horizon() {
        let p = RingPoint {
            about: About::Retro,
            radius_deg: 2.0,
            azimuth_deg: 0.0,
        };
        let g = p.geometry(30.0);
        assert!((g.theta_o_deg - 32.0).abs() < 1e-4 && g.dphi_deg.abs() < 1e-4, "{g:?}");
        let g = RingPoint { azimuth_deg: 180.0, ..p }.geometry(30.0);
        assert!((g.theta_o_deg - 28.0).abs() < 1e-4 && g.dphi_deg.abs() < 1e-3, "{g:?}");
        let g = RingPoint { about: About::Mirror, ..p }.geometry(30.0);
        assert!(
            (g.theta_o_deg - 32.0).abs() < 1e-4 && (g.dphi_deg.abs() - 180.0).abs() < 1e-4,
            "{g:?}"
        );
    }

    #[test]
    fn the_reference_patterns_hold_the_cea_heads_retro_zone() {
        let p = LobePatterns::cea();
        assert_eq!(p.retro.count(), Some(320));
        assert_eq!(p.count(), Some(400));
        assert!(p.retro.radii_deg.iter().all(|r| *r < 5.0));
    }

    /// The visit order holds every view once, and goes around each
    /// direction once: consecutive views on one azimuth or the next.
    #[test]
    fn the_views_are_visited_once_azimuth_by_azimuth() {
        let p = LobePatterns::cea();
        let n = p.count().unwrap();
        let order: Vec<u32> = (0..n).map(|k| p.visited(k).unwrap()).collect();
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..n).collect::<Vec<_>>());
        assert!(p.visited(n).is_none());
        for w in order.windows(2) {
            let (a, b) = (p.ring_point(w[0]).unwrap(), p.ring_point(w[1]).unwrap());
            if a.about == b.about {
                let step = (b.azimuth_deg - a.azimuth_deg).abs();
                assert!(
                    step < 1e-3 || (step - 11.25).abs() < 1e-3 || (step - 22.5).abs() < 1e-3,
                    "{a:?} → {b:?}"
                );
            }
        }
    }

    #[test]
    fn malformed_patterns_are_refused() {
        let bad = |radii: &[f32], az: u16| Rings::from_radii(radii, az).count();
        assert_eq!(bad(&[], 0), Some(0));
        assert_eq!(bad(&[1.0], 0), None);
        assert_eq!(bad(&[0.0], 8), None);
        assert_eq!(bad(&[-1.0], 8), None);
        assert_eq!(bad(&[f32::NAN], 8), None);
        assert_eq!(bad(&[31.0], 8), None);
        assert_eq!(bad(&[1.0], 361), None);
        let p = LobePatterns {
            retro: Rings::from_radii(&[1.0], 4),
            mirror: Rings::none(),
        };
        assert_eq!(p.count(), Some(4));
        assert!(p.ring_point(4).is_none() && p.point(30.0, 3).is_some());
    }
}
