//! The head's sanity check on the simulated head: with the material's model
//! loaded and a 3σ band, dust specks (five times the model value at a few
//! points) are flagged and measured again, and clean points are not flagged.

use gonio::cli::in_process::Simulated;
use gonio_acquire::operator::Operator;
use gonio_acquire::session::{Session, Setup};
use gonio_brdf::{Directions, Material, Specimen};
use gonio_shared::icd::{MeasureEndpoint, MeasureRequest, SanityEndpoint, StatusEndpoint};
use gonio_shared::{AngleRange, DetectionSettings, Geometry, SampleFlags, SanityConfig, ScanSpec};
use gonio_sim::SimConfig;
use gonio_tests::scanning::scan_and_read;
use std::collections::BTreeSet;
use std::sync::Arc;

#[tokio::test]
async fn dust_is_flagged_and_clean_data_is_not() {
    let spec = ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[30.0, 60.0]).unwrap(),
        theta_o: AngleRange::new(0.0, 75.0, 3.0),
        dphi: AngleRange::new(0.0, 180.0, 45.0),
        first_order: 0,
        sweep: None,
        patterns: None,
    };
    let dust = [
        Geometry::new(30.0, 45.0, 90.0),
        Geometry::new(60.0, 12.0, 180.0),
        Geometry::new(30.0, 9.0, 135.0),
        Geometry::new(60.0, 51.0, 45.0),
    ];
    let sim = SimConfig {
        dust: dust.to_vec(),
        material: Specimen::Model(Material::tape()),
        ..SimConfig::default()
    };
    let material = Material::tape();
    let setup = Setup {
        settings: DetectionSettings::default(),
        learn_at: None,
        learning_periods: 0,
    };
    let mut session = Session::connect(Arc::new(Simulated(sim.clone())), setup, Operator::Silent)
        .await
        .unwrap();
    session.start().await.unwrap();
    let head = session.head();

    // The instrument constant from one clean point, as a reference plate would give it.
    let at = Geometry::new(30.0, 20.0, 90.0);
    let s = head.request::<MeasureEndpoint>(&MeasureRequest { at: Some(at) }).await.unwrap();
    let d = Directions::from_degrees(at.theta_i_deg as f64, at.theta_o_deg as f64, at.dphi_deg as f64);
    let current = s.signal.amplitude_v as f64 / s.signal.gain_v_per_a as f64 / (material.eval(&d) * d.cos_o());
    head.request::<SanityEndpoint>(&SanityConfig {
        model: material.sanity_model().unwrap(),
        current_a_per_sr_inv: current as f32,
        splitter_factor: sim.photodiode.splitter_factor as f32,
        rel_tol: 0.02,
        abs_tol_v: 2.0e-4,
        k_noise: 3.0,
        remeasure: true,
    })
    .await
    .unwrap();

    let dir = tempfile::tempdir().unwrap();
    let (_, rows) = scan_and_read(&mut session, &spec, dir.path()).await;
    let status = session.head().request::<StatusEndpoint>(&()).await.unwrap();
    session.close().await;

    let dusty: BTreeSet<u32> = (0..spec.len())
        .filter(|&i| {
            let g = spec.point(i).unwrap();
            dust.iter()
                .any(|d| d.theta_i_deg == g.theta_i_deg && d.theta_o_deg == g.theta_o_deg && d.dphi_deg == g.dphi_deg)
        })
        .collect();
    assert_eq!(dusty.len(), dust.len());
    let flagged: BTreeSet<u32> = rows
        .iter()
        .filter(|r| r.sample_flags().contains(SampleFlags::MODEL_MISMATCH))
        .map(|r| r.index.unwrap())
        .collect();
    assert!(dusty.is_subset(&flagged), "dust {dusty:?}, flagged {flagged:?}");
    let false_flags = flagged.difference(&dusty).count();
    let clean = rows.len() - dusty.len();
    eprintln!(
        "{} dust specks flagged of {}; {false_flags} of {clean} clean points flagged",
        dusty.intersection(&flagged).count(),
        dusty.len()
    );
    assert!(
        (false_flags as f64) < 0.01 * clean as f64,
        "{false_flags} of {clean} clean points flagged: {:?}",
        flagged.difference(&dusty).collect::<Vec<_>>()
    );
    // Every mismatch was measured once more, and the head counted it.
    for r in rows.iter().filter(|r| dusty.contains(&r.index.unwrap())) {
        assert!(r.sample_flags().contains(SampleFlags::REMEASURED), "{r:?}");
    }
    assert_eq!(status.samples_remeasured as usize, flagged.len());
    assert!(status.sanity_loaded);
}
