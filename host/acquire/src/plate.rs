//! The reference-plate protocol (`gonio scan --reference-plate`): the plate is
//! mounted, measured at a few geometries inside and outside the beam
//! splitter's zone, and swapped for the sample, with the head homed and the
//! laser's clock running throughout (so `gonio calibrate` can tie the
//! plate's scale to the sample's drift monitor without a gap).

use crate::client::HeadClient;
use crate::operator::Operator;
use crate::target::{Holder, Target};
use anyhow::{Context, Result};
use gonio_scan_dir::samples;
use gonio_shared::icd::{MeasureEndpoint, MeasureRequest};
use gonio_shared::Geometry;
use std::path::Path;

/// Plate geometries (θi, θo, Δφ in degrees): pure retroreflection (through
/// the splitter) and off-retro directions clear of the blind zone. Every
/// value seen through the splitter is divided by its factor `T`, which these
/// retro points alone set: twelve of them, so that `T`'s standard error has
/// eleven degrees of freedom. With four (three degrees of freedom) that
/// error was itself a poor estimate: repeat scans scattered 1.6× its
/// prediction at the retro peaks.
const PLATE_POINTS: [(f32, f32, f32); 24] = [
    (10.0, 10.0, 0.0),
    (15.0, 15.0, 0.0),
    (20.0, 20.0, 0.0),
    (25.0, 25.0, 0.0),
    (30.0, 30.0, 0.0),
    (35.0, 35.0, 0.0),
    (40.0, 40.0, 0.0),
    (45.0, 45.0, 0.0),
    (50.0, 50.0, 0.0),
    (55.0, 55.0, 0.0),
    (60.0, 60.0, 0.0),
    (65.0, 65.0, 0.0),
    (30.0, 0.0, 0.0),
    (30.0, 20.0, 90.0),
    (30.0, 40.0, 90.0),
    (30.0, 60.0, 90.0),
    (30.0, 20.0, 180.0),
    (30.0, 40.0, 180.0),
    (30.0, 60.0, 180.0),
    (15.0, 45.0, 180.0),
    (45.0, 15.0, 90.0),
    (60.0, 30.0, 180.0),
    (60.0, 10.0, 90.0),
    (15.0, 60.0, 0.0),
];

/// Measures the plate, writes `reference.csv`, and puts the sample back.
pub async fn measure_plate(head: &HeadClient, target: &dyn Target, dir: &Path, operator: Operator) -> Result<()> {
    target.mount(Holder::ReferencePlate, operator)?;
    let mut samples = Vec::with_capacity(PLATE_POINTS.len());
    for (ti, to, dp) in PLATE_POINTS {
        let s = head
            .request::<MeasureEndpoint>(&MeasureRequest {
                at: Some(Geometry::new(ti, to, dp)),
            })
            .await
            .with_context(|| format!("measuring the reference plate at ({ti}°, {to}°, {dp}°)"))?;
        samples.push(s);
    }
    let path = samples::write_reference(dir, &samples)?;
    target.mount(Holder::Sample, operator)?;
    operator.notice(format_args!(
        "reference plate measured at {} geometries: {}",
        PLATE_POINTS.len(),
        path.display()
    ));
    Ok(())
}
