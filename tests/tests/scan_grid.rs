//! The scan grid shared by head and host: canonical indexing and the
//! serpentine visit order.

use gonio_shared::{AngleRange, ScanSpec};
use proptest::prelude::*;
use std::collections::BTreeSet;

fn grid() -> impl Strategy<Value = ScanSpec> {
    (1usize..=4, 1u32..12, 1u32..12).prop_map(|(n_ti, n_to, n_dp)| ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[10.0, 20.0, 30.0, 40.0][..n_ti]).unwrap(),
        theta_o: AngleRange::new(0.0, 3.0 * (n_to - 1) as f32, 3.0),
        dphi: AngleRange::new(-180.0, -180.0 + 10.0 * (n_dp - 1) as f32, 10.0),
        first_order: 0,
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
