//! The scan grid shared by head and host: canonical indexing, the
//! fallback serpentine order (`index_at_order`, a sweep scan's too), and
//! the host's visit order against its lower bound.

use gonio_acquire::scan_order::{lower_bound, scan_time, visit_order, ScanTime};
use gonio_firmware::config::REFERENCE;
use gonio_firmware::kinematics;
use gonio_firmware::motion::{target_steps, PARK};
use gonio_shared::{row_turn, AngleRange, Geometry, LobePatterns, Rings, ScanSpec, SweepScan, Visit};
use proptest::prelude::*;
use std::collections::BTreeSet;

fn grid() -> impl Strategy<Value = ScanSpec> {
    (1usize..=4, 1u32..12, 1u32..12).prop_map(|(n_ti, n_to, n_dp)| ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[10.0, 20.0, 30.0, 40.0][..n_ti]).unwrap(),
        theta_o: AngleRange::new(0.0, 3.0 * (n_to - 1) as f32, 3.0),
        dphi: AngleRange::new(-180.0, -180.0 + 10.0 * (n_dp - 1) as f32, 10.0),
        first_order: 0,
        sweep: None,
        patterns: None,
    })
}

proptest! {
    #[test]
    fn the_visit_order_is_a_permutation_of_neighbours(spec in grid()) {
        let n = spec.len();
        let order: Vec<u32> = (0..n).map(|o| spec.index_at_order(o).unwrap()).collect();
        prop_assert_eq!(order.iter().collect::<BTreeSet<_>>().len() as u32, n);
        prop_assert!(spec.index_at_order(n).is_none() && spec.point(n).is_none());
        // Within one incidence, consecutive points differ by one step of one angle.
        for w in order.windows(2) {
            let (a, b) = (spec.point(w[0]).unwrap(), spec.point(w[1]).unwrap());
            if a.theta_i_deg != b.theta_i_deg {
                continue;
            }
            let steps = ((a.theta_o_deg - b.theta_o_deg).abs() / 3.0).round() + ((a.dphi_deg - b.dphi_deg).abs() / 10.0).round();
            prop_assert_eq!(steps, 1.0, "{:?} -> {:?}", a, b);
        }
    }
}

proptest! {
    /// A sweep scan visits every position once: at each incidence its retro
    /// point first, then its rows, the first outward from the retro
    /// direction and each next one back, Δφ's way back at every other
    /// incidence.
    #[test]
    fn a_sweep_scan_visits_each_incidence_retro_point_first_then_its_rows(n_ti in 1usize..=8, n_dp in 1u32..=37) {
        // Up to 8 incidences, up to the whole circle of Δφ (36 rows a step
        // short of it, 37 from −180° to 180°, one great circle).
        let spec = ScanSpec {
            theta_i_deg: heapless::Vec::from_slice(&[10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0][..n_ti]).unwrap(),
            theta_o: AngleRange::new(0.0, 87.0, 3.0),
            dphi: AngleRange::new(-180.0, -180.0 + 10.0 * (n_dp - 1) as f32, 10.0),
            first_order: 0,
            sweep: Some(SweepScan { speed_dps: 30.0, periods_per_sample: 8, lobe: None }),
            patterns: None,
        };
        let (n, rows) = (spec.len(), spec.dphi.count().unwrap());
        prop_assert_eq!(n, spec.theta_i_deg.len() as u32 * (rows + 1));
        let order: Vec<u32> = (0..n).map(|o| spec.index_at_order(o).unwrap()).collect();
        prop_assert_eq!(order.iter().collect::<BTreeSet<_>>().len() as u32, n);
        prop_assert!(spec.index_at_order(n).is_none() && spec.visit(n, n).is_none());
        let span = (spec.dphi.at(0), spec.dphi.at(rows - 1));
        for (o, &i) in (0..).zip(&order) {
            let (a, k) = (o / (rows + 1), o % (rows + 1));
            let ti = spec.theta_i_deg[a as usize];
            match spec.visit(i, o).unwrap() {
                Visit::Point(g) => prop_assert!(k == 0 && g == Geometry::new(ti, ti, 0.0), "{o}: {g:?}"),
                Visit::Row(r) => {
                    prop_assert!(k > 0 && r.theta_i_deg == ti && r.outward == (k % 2 == 1), "{o}: {r:?}");
                    let along = if a % 2 == 0 { k - 1 } else { rows - k };
                    prop_assert_eq!(r.dphi_deg, row_turn::row_dphi_deg(ti, span.0, span.1, along, rows));
                }
            }
        }
    }
}

#[test]
fn ranges_include_their_stop_and_refuse_nonsense() {
    assert_eq!(AngleRange::new(0.0, 90.0, 3.0).count(), Some(31));
    assert_eq!(AngleRange::new(-180.0, 180.0, 10.0).count(), Some(37));
    assert_eq!(AngleRange::new(0.0, 1.0, 0.3).count(), Some(4));
    assert_eq!(AngleRange::new(0.0, 0.0, 1.0).count(), Some(1));
    for bad in [
        AngleRange::new(0.0, 90.0, 0.0),
        AngleRange::new(10.0, 0.0, 1.0),
        AngleRange::new(0.0, f32::NAN, 1.0),
        AngleRange::new(0.0, 720.0, 1.0),
    ] {
        assert_eq!(bad.count(), None, "{bad:?}");
    }
    let mut s = ScanSpec::belcour();
    assert_eq!(s.validate(), Ok(3441));
    s.first_order = 3442;
    assert!(s.validate().is_err());
}

/// Small grids on the reference head, some with unreachable points, some
/// from θo = 0 (where every Δφ is the same stage target: moves of no time).
fn small_grid() -> impl Strategy<Value = ScanSpec> {
    let to0 = prop_oneof![Just(0.0f32), 0.0f32..80.0];
    (1usize..=2, 1u32..4, 1u32..4, to0, 1.0f32..12.0, 1.0f32..40.0).prop_map(|(n_ti, n_to, n_dp, to0, to_step, dp_step)| ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[20.0, 55.0][..n_ti]).unwrap(),
        theta_o: AngleRange::new(to0, to0 + to_step * (n_to - 1) as f32, to_step),
        dphi: AngleRange::new(-170.0, -170.0 + dp_step * (n_dp - 1) as f32, dp_step),
        first_order: 0,
        sweep: None,
        patterns: None,
    })
}

/// Every order of `points` (Heap's algorithm), each handed to `visit`.
fn each_order(points: &mut [u32], k: usize, visit: &mut impl FnMut(&[u32])) {
    if k <= 1 {
        visit(points);
        return;
    }
    for i in 0..k {
        each_order(points, k - 1, visit);
        let j = if k % 2 == 0 { i } else { 0 };
        points.swap(j, k - 1);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// The lower bound is one: no order of the points, the plan's or any
    /// other, takes less, even from the best start there is, the first
    /// point itself (every order is tried on grids of up to 6 points); and
    /// the plan visits every point once.
    #[test]
    fn no_order_beats_the_lower_bound(spec in small_grid()) {
        let cfg = &REFERENCE;
        let (settle, integration) = (0.05, 0.1);
        let (bound, _) = lower_bound(cfg, &spec, settle, integration).expect("a small grid");
        let plan: Vec<u32> = visit_order(cfg, &spec, PARK).collect();
        prop_assert_eq!(plan.iter().collect::<BTreeSet<_>>().len() as u32, spec.len());
        prop_assert_eq!(plan.len() as u32, spec.len());
        // The chip's planning is not in the bound: compare what the stages and the detector take.
        let physical = |t: ScanTime| t.total_s() - t.planning_s;
        let planned = scan_time(cfg, &spec, plan.iter().copied(), PARK, settle, integration);
        prop_assert_eq!(planned.measured, bound.measured);
        prop_assert!(physical(planned) >= bound.total_s() - 1e-9, "plan {} < bound {}", physical(planned), bound.total_s());
        let mut points: Vec<u32> = (0..spec.len()).collect();
        let mut best = f64::INFINITY;
        if points.len() <= 6 {
            let n = points.len();
            let target = |i: u32| kinematics::inverse(cfg, &spec.point(i).unwrap()).ok().map(|a| target_steps(cfg, &a));
            each_order(&mut points, n, &mut |order| {
                let from = order.iter().find_map(|&i| target(i)).unwrap_or(PARK);
                best = best.min(physical(scan_time(cfg, &spec, order.iter().copied(), from, settle, integration)));
            });
            prop_assert!(best >= bound.total_s() - 1e-9, "an order takes {} < bound {}", best, bound.total_s());
        }
    }
}

/// The Belcour grid's plan against its bound (`scan-bench` quotes the
/// figure; this keeps the planner from sliding back to the greedy path,
/// about 1.05 times the bound by this measure).
#[test]
fn the_belcour_plan_is_within_four_percent_of_the_bound() {
    let (cfg, spec) = (&REFERENCE, ScanSpec::belcour());
    let (bound, _) = lower_bound(cfg, &spec, 0.05, 0.1).expect("3 316 points");
    let plan = scan_time(cfg, &spec, visit_order(cfg, &spec, PARK), PARK, 0.05, 0.1);
    let ratio = (plan.total_s() - plan.planning_s) / bound.total_s();
    assert!(ratio < 1.04, "plan / bound = {ratio}");
}

proptest! {
    /// A scan with lobe patterns visits every position once, grid or sweep:
    /// at each incidence its grid points (or its retro point, then its
    /// pattern, then its rows), then its pattern points, each the view of
    /// its ring at the incidence, and the rows keep their order and their
    /// alternation outward and back as without a pattern.
    #[test]
    fn a_patterned_scan_visits_each_position_once_and_its_rings_where_they_are(
        n_ti in 1usize..=3, n_dp in 2u32..=8, rings in 1usize..=4, azimuths in 1u16..=12, sweep in any::<bool>(),
    ) {
        let radii: Vec<f32> = (0..rings).map(|k| 0.5 + k as f32).collect();
        let patterns = LobePatterns {
            retro: Rings { radii_deg: heapless::Vec::from_slice(&radii).unwrap(), azimuths },
            mirror: Rings { radii_deg: heapless::Vec::from_slice(&[2.0]).unwrap(), azimuths: 4 },
        };
        let per_incidence = patterns.count().unwrap();
        let bare = ScanSpec {
            theta_i_deg: heapless::Vec::from_slice(&[20.0, 40.0, 60.0][..n_ti]).unwrap(),
            theta_o: AngleRange::new(0.0, 87.0, 3.0),
            dphi: AngleRange::new(-180.0, -180.0 + 30.0 * (n_dp - 1) as f32, 30.0),
            first_order: 0,
            sweep: sweep.then_some(SweepScan { speed_dps: 30.0, periods_per_sample: 8, lobe: None }),
            patterns: None,
        };
        let spec = ScanSpec { patterns: Some(patterns.clone()), ..bare.clone() };
        let n = spec.len();
        prop_assert_eq!(n, bare.len() + n_ti as u32 * per_incidence);
        prop_assert_eq!(spec.pattern_points(), n_ti as u32 * per_incidence);
        let order: Vec<u32> = (0..n).map(|o| spec.index_at_order(o).unwrap()).collect();
        prop_assert_eq!(order.iter().collect::<BTreeSet<_>>().len() as u32, n);
        prop_assert!(spec.index_at_order(n).is_none() && spec.visit(n, n).is_none());
        let block = n / n_ti as u32;
        let base = block - per_incidence;
        let mut bare_rows = Vec::new();
        let mut rows = Vec::new();
        for (o, &i) in order.iter().enumerate() {
            let (a, c) = (i / block, i % block);
            let ti = spec.theta_i_deg[a as usize];
            let v = spec.visit(i, o as u32).unwrap();
            if c >= base {
                // A pattern point: the ring's view, at rest.
                prop_assert_eq!(v, Visit::Point(patterns.point(ti, c - base).unwrap()));
            } else if let Visit::Row(r) = v {
                rows.push(r);
            } else if !sweep {
                prop_assert_eq!(v, Visit::Point(bare.point(a * base + c).unwrap()));
            }
        }
        if sweep {
            for o in 0..bare.len() {
                let i = bare.index_at_order(o).unwrap();
                if let Some(Visit::Row(r)) = bare.visit(i, o) {
                    bare_rows.push(r);
                }
            }
            prop_assert_eq!(rows, bare_rows);
        }
    }
}
