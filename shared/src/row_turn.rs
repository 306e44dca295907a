//! Where a sweep scan's rows lie. A row is the arm's view circle, a great
//! circle through the laser (the retro direction `l`), so every row's plane
//! contains `l` and rows differ by a turn `γ` about it: two rows are nowhere
//! farther apart than the angle between their planes, `|Δγ|`, which they
//! reach 90° from the laser. The rows of a θi are turned evenly, between the
//! rows that meet the horizon at the Δφ span's ends, so for a span whose
//! ends lie at 0°, ±90° or ±180° (the Belcour grid's −180°..180°) they are
//! the Δφ step apart: never farther apart than the grid's Δφ lines are at
//! the horizon. A span short of the whole circle by a step or less (its
//! next value would reach its first again, or pass it) has its rows spread
//! evenly around the whole turn from its first, so they are at most the
//! step apart there too, the last beside the first included. Between other ends the turn they span
//! is up to `1/cos θi` times the Δφ span (next to the plane of incidence),
//! and so is their spacing.
//!
//! The turn fixes where the row meets the sample's horizon: with the sample
//! tilted so that its normal lies at θi from `l`, `tan Δφ_H = cos θi·tan γ`
//! (γ = 0 is the retro half of the plane of incidence, γ = ±180° its mirror
//! half; the two agree at 0, ±90° and ±180°). Rows evenly spaced at the
//! horizon instead would be turned up to `1/cos θi` times the step apart
//! next to the plane of incidence (19.4° for 10° steps at θi = 60°): across
//! the mirror lobe at 60° twice as far apart as the grid's points, and a
//! model outside the material's family, fitted to them, settles elsewhere
//! than on the grid (`docs/decisions/009-rows-turned-about-the-laser.md`).

use libm::{atan2f, cosf, sinf};

const DEG: f32 = core::f32::consts::PI / 180.0;

/// The turn (deg) of the row that meets the horizon at `dphi_deg`, at an
/// incidence of cosine `cos_i`: within 90° of `dphi_deg` (same quadrant), so
/// a span beyond ±180° keeps its order.
fn turn_deg(cos_i: f32, dphi_deg: f32) -> f32 {
    let g = atan2f(sinf(dphi_deg * DEG), cos_i * cosf(dphi_deg * DEG)) / DEG;
    beside(g, dphi_deg)
}

/// The azimuth (deg) at which a row turned by `turn` meets the horizon.
fn horizon_deg(cos_i: f32, turn: f32) -> f32 {
    let h = atan2f(cos_i * sinf(turn * DEG), cosf(turn * DEG)) / DEG;
    beside(h, turn)
}

/// `angle` moved by whole turns to within half a turn of `near`.
fn beside(angle: f32, near: f32) -> f32 {
    angle - 360.0 * libm::roundf((angle - near) / 360.0)
}

/// Where the `k`-th of `n` rows of a sweep scan at incidence `theta_i_deg`
/// meets the horizon (deg), its rows turned evenly about the laser from the
/// one meeting it at `first_deg` to the one meeting it at `last_deg` (the
/// grid's Δφ span of `n` values): those two exactly, the others between, to
/// some 10⁻⁵°; or, for a span that closes the circle short of its first
/// value again, around the whole turn from the first. Ten trigonometric
/// calls in f32, the chip's own floating point (in f64, emulated on the M4,
/// they cost a row 29 000 instructions more: `chip-bench`).
pub fn row_dphi_deg(theta_i_deg: f32, first_deg: f32, last_deg: f32, k: u32, n: u32) -> f32 {
    if k == 0 || n < 2 {
        return first_deg;
    }
    let step = (last_deg - first_deg) / (n - 1) as f32;
    let closes = n as f32 * step >= 360.0 - CLOSE_DEG && last_deg - first_deg < 360.0 - CLOSE_DEG;
    if k >= n - 1 && !closes {
        return last_deg;
    }
    let cos_i = cosf(theta_i_deg * DEG);
    let a = turn_deg(cos_i, first_deg);
    let turn = match closes {
        true => a + 360.0 * k.min(n - 1) as f32 / n as f32,
        false => a + (turn_deg(cos_i, last_deg) - a) * k as f32 / (n - 1) as f32,
    };
    horizon_deg(cos_i, turn)
}

/// A span within this (deg) of a whole turn is one: the f32 rounding of its
/// values.
const CLOSE_DEG: f32 = 1e-3;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_belcour_rows_turn_ten_degrees_apart() {
        // θi = 60°: the rows next to the mirror half-plane meet the horizon
        // at 174.96° and 169.69°, next to Δφ = 90° 19.4° apart.
        let at = |k| row_dphi_deg(60.0, -180.0, 180.0, k, 37);
        assert_eq!((at(0), at(18), at(36)), (-180.0, 0.0, 180.0));
        assert!((at(35) - 174.96).abs() < 0.01, "{}", at(35));
        assert!((at(34) - 169.69).abs() < 0.01, "{}", at(34));
        assert!((at(27) - 90.0).abs() < 1e-4 && (at(27) - at(26) - 19.4).abs() < 0.05);
        // Normal incidence: every turn is its own azimuth.
        assert!((0..37).all(|k| (row_dphi_deg(0.0, -180.0, 180.0, k, 37) - (-180.0 + 10.0 * k as f32)).abs() < 1e-4));
    }

    proptest! {
        /// The turn and the horizon azimuth are one another's inverse, and
        /// the rows keep the span's order from its first value, beyond ±180°
        /// as well: to its last, or, for a span that closes the circle, a
        /// whole turn shared evenly.
        #[test]
        fn rows_keep_their_span_in_order(
            ti in 0.0f32..85.0, first in -400.0f32..400.0, width in 0.0f32..=360.0, n in 2u32..60,
        ) {
            // (Beyond 85° the f32 round trip loses 1e-3° at some azimuths:
            // at θi = 88.7°, cos θi = 0.023 scales the turn's rounding 40×.)
            let (last, c) = (first + width, cosf(ti * DEG));
            let d = (first + 37.0) % 360.0 - 180.0;
            prop_assert!((horizon_deg(c, turn_deg(c, d)) - d).abs() < 1e-3);
            let rows: Vec<f32> = (0..n).map(|k| row_dphi_deg(ti, first, last, k, n)).collect();
            prop_assert_eq!(rows[0], first);
            prop_assert!(rows.windows(2).all(|w| w[1] - w[0] >= -1e-3), "{rows:?}");
            let closes = n as f32 * width / (n - 1) as f32 >= 360.0 - CLOSE_DEG && width < 360.0 - CLOSE_DEG;
            if closes {
                let turns: Vec<f32> = rows.iter().map(|&r| turn_deg(c, r)).collect();
                let apart = 360.0 / n as f32;
                prop_assert!(turns.windows(2).all(|w| (w[1] - w[0] - apart).abs() < 0.01), "{turns:?}");
            } else {
                prop_assert_eq!(rows[n as usize - 1], last);
            }
            // Past the last row, and any n: the span's ends, no overflow.
            prop_assert_eq!(row_dphi_deg(ti, first, last, 0, 0), first);
            let beyond = row_dphi_deg(ti, first, last, u32::MAX, n);
            prop_assert!(beyond.is_finite() && (closes || beyond == last));
        }
    }
}
