//! Sweeps on the simulated head driven directly (no link): the samples, the
//! head time they took, and the true geometry each sample saw, from the
//! motor angles the simulated head logs at every conversion.

use gonio_brdf::frame::angle_between;
use gonio_brdf::Directions;
use gonio_firmware::kinematics;
use gonio_firmware::Head;
use gonio_shared::icd::{HomeRequest, MeasureRequest};
use gonio_shared::{AxisAngles, Fault, Geometry, Sample, SweepReport, SweepRequest, SweptSample};
use gonio_sim::{build, clock, SimBoard, SimConfig, World};
use std::cell::RefCell;
use std::rc::Rc;

/// A homed simulated head and its world.
pub struct SimHead {
    pub head: Head<SimBoard>,
    pub world: Rc<RefCell<World>>,
}

/// A sweep's samples and what it took.
pub struct Swept {
    pub samples: Vec<SweptSample>,
    pub report: SweepReport,
    /// Head time from the request to the answer (s): the move to the start,
    /// settling, ranging and the sweep itself.
    pub head_s: f64,
    /// The true motor angles (degrees) at every conversion (time in s).
    pub log: Vec<(f64, [f64; 3])>,
}

impl SimHead {
    pub fn homed(cfg: &SimConfig) -> Self {
        let (mut head, world) = build(cfg);
        clock::run(&world, head.home(HomeRequest::ALL)).expect("the simulated head homes");
        SimHead { head, world }
    }

    pub fn now_s(&self) -> f64 {
        self.world.borrow().t_s
    }

    /// Runs one sweep, logging the motors at every conversion.
    pub fn sweep(&mut self, req: SweepRequest) -> Result<Swept, Fault> {
        self.world.borrow_mut().sample_log = Some(Vec::new());
        let t0 = self.now_s();
        let mut samples = Vec::new();
        let r = clock::run(&self.world, self.head.sweep(req, |s| samples.push(s)));
        let log = self.world.borrow_mut().sample_log.take().unwrap_or_default();
        Ok(Swept {
            report: r?,
            samples,
            head_s: self.now_s() - t0,
            log,
        })
    }

    /// The geometry the motors truly stand at.
    pub fn motor_geometry(&self) -> Geometry {
        let a = self.world.borrow().angles();
        geometry(&AxisAngles {
            omega_deg: a[0] as f32,
            tau_deg: a[1] as f32,
            psi_deg: a[2] as f32,
        })
    }

    /// Measures at rest at `g` (after moving there).
    pub fn measure(&mut self, g: Geometry) -> Result<Sample, Fault> {
        clock::run(&self.world, self.head.measure(MeasureRequest { at: Some(g) }))
    }
}

/// The geometry of stage angles.
pub fn geometry(a: &AxisAngles) -> Geometry {
    kinematics::forward(a)
}

/// The true geometries of the conversions a swept sample integrated, from
/// the motor angles logged at each.
pub fn conversions(log: &[(f64, [f64; 3])], s: &SweptSample) -> Vec<Geometry> {
    // The start is in whole µs; conversions are some 68 µs apart.
    let t0 = s.start_us as f64 * 1e-6 - 1e-6;
    let t1 = t0 + s.duration_s as f64;
    log.iter()
        .filter(|(t, _)| *t >= t0 && *t < t1)
        .map(|(_, a)| {
            geometry(&AxisAngles {
                omega_deg: a[0] as f32,
                tau_deg: a[1] as f32,
                psi_deg: a[2] as f32,
            })
        })
        .collect()
}

/// Light and view directions of a geometry, in the sample's frame.
fn directions(g: &Geometry) -> [[f64; 3]; 2] {
    let d = Directions::from_degrees(g.theta_i_deg as f64, g.theta_o_deg as f64, g.dphi_deg as f64);
    [d.l, d.v]
}

/// How far (degrees) a sample's tag (the geometry at the middle of its stage
/// angles) lies from the true mean geometry of its conversions: the larger
/// of the angles between the tag's and the mean light direction and between
/// the tag's and the mean view direction. Angles on the sphere, not
/// differences of θ and Δφ, which mean nothing near the pole.
pub fn tag_error_deg(log: &[(f64, [f64; 3])], s: &SweptSample) -> f64 {
    let seen = conversions(log, s);
    if seen.is_empty() {
        // A sample no conversion is found for cannot be checked: it fails.
        return f64::INFINITY;
    }
    let mut mean = [[0.0; 3]; 2];
    for g in &seen {
        for (m, d) in mean.iter_mut().zip(directions(g)) {
            for i in 0..3 {
                m[i] += d[i];
            }
        }
    }
    let tag = directions(&geometry(&s.mid_axes()));
    angle_between(tag[0], mean[0]).max(angle_between(tag[1], mean[1])).to_degrees()
}

/// The largest [`tag_error_deg`] of a sweep's samples.
pub fn tag_error_deg_max(swept: &Swept) -> f64 {
    swept.samples.iter().map(|s| tag_error_deg(&swept.log, s)).fold(0.0, f64::max)
}
