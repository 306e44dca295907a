//! `scan.json`: what a scan was asked to do, written before its first sample
//! so `gonio scan --resume DIR` can finish an interrupted scan exactly.

use super::detector::DetectorPlan;
use super::simulated::Simulated;
use crate::scan::Monitor;
use crate::scan_dir::ScanDir;
use crate::target::{Port, Target};
use anyhow::{bail, Context, Result};
use gonio_brdf::Specimen;
use gonio_shared::scan::SWEEP_LAYOUT_SINCE;
use gonio_shared::{ScanSpec, PROTOCOL_VERSION};
use gonio_sim::faults::Faults;
use gonio_sim::{Imperfections, SimConfig};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

/// Which head.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlanTarget {
    Sim {
        material: Specimen,
        seed: u64,
        #[serde(default)]
        laser_drift: f64,
        #[serde(default)]
        clock_start_s: f64,
        #[serde(default)]
        imperfections: Imperfections,
    },
    Port {
        path: String,
    },
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScanPlan {
    pub target: PlanTarget,
    pub spec: ScanSpec,
    pub detector: DetectorPlan,
    /// Laser-drift monitor: a geometry measured before, every so many points
    /// during, and after the scan.
    #[serde(default)]
    pub monitor: Option<Monitor>,
    /// Measure the reference plate before the scan (`reference.csv`).
    #[serde(default)]
    pub reference_plate: bool,
    /// Faults injected into a simulated head: not part of the plan (a
    /// resume runs on the repaired head).
    #[serde(skip)]
    pub faults: Faults,
    /// The protocol the scan was planned under (0: by a gonio that did not
    /// keep it): a sweep scan's positions depend on it.
    #[serde(default)]
    pub protocol: u16,
}

impl ScanPlan {
    /// A plan for the head at port `path`.
    pub fn at_port(path: &str, spec: &ScanSpec, detector: &DetectorPlan) -> Self {
        Self::new(PlanTarget::Port { path: path.to_string() }, spec, detector, Faults::default())
    }

    /// A plan for the simulated head `c`; its faults act on this run only.
    pub fn simulated(c: &SimConfig, spec: &ScanSpec, detector: &DetectorPlan) -> Self {
        let target = PlanTarget::Sim {
            material: c.material.clone(),
            seed: c.seed,
            laser_drift: c.photodiode.laser_drift,
            clock_start_s: c.clock_start_s,
            imperfections: (*c.imperfections).clone(),
        };
        Self::new(target, spec, detector, c.faults.clone())
    }

    fn new(target: PlanTarget, spec: &ScanSpec, detector: &DetectorPlan, faults: Faults) -> Self {
        ScanPlan {
            target,
            spec: spec.clone(),
            detector: detector.clone(),
            monitor: None,
            reference_plate: false,
            faults,
            protocol: PROTOCOL_VERSION,
        }
    }

    /// The head this plan runs on.
    pub fn target(&self) -> Arc<dyn Target> {
        match &self.target {
            PlanTarget::Sim {
                material,
                seed,
                laser_drift,
                clock_start_s,
                imperfections,
            } => {
                let mut c = SimConfig {
                    material: material.clone(),
                    seed: *seed,
                    clock_start_s: *clock_start_s,
                    faults: self.faults.clone(),
                    imperfections: Box::new(imperfections.clone()),
                    ..SimConfig::default()
                };
                c.photodiode.laser_drift = *laser_drift;
                Arc::new(Simulated(c))
            }
            PlanTarget::Port { path } => Arc::new(Port(path.clone())),
        }
    }

    /// The material on a simulated head (what the run record keeps as the truth).
    pub fn material(&self) -> Option<Specimen> {
        match &self.target {
            PlanTarget::Sim { material, .. } => Some(material.clone()),
            PlanTarget::Port { .. } => None,
        }
    }

    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = ScanDir::new(dir).plan();
        std::fs::write(&path, serde_json::to_string_pretty(self)? + "\n").with_context(|| format!("writing {}", path.display()))
    }

    /// The plan of the scan in `dir`, to resume: refused for a sweep scan
    /// planned before its positions took their place
    /// ([`SWEEP_LAYOUT_SINCE`]: the rows turned evenly about the laser, each
    /// incidence's retro point first) or by a later gonio, so that no scan
    /// mixes two layouts.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = ScanDir::new(dir).plan();
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{} holds no scan to resume ({} missing)", dir.display(), path.display()))?;
        let plan: Self = serde_json::from_str(&text).with_context(|| format!("reading {}", path.display()))?;
        if plan.spec.sweep.is_some() && !(SWEEP_LAYOUT_SINCE..=PROTOCOL_VERSION).contains(&plan.protocol) {
            let by = match plan.protocol {
                0 => "by an earlier gonio".to_string(),
                p => format!("under protocol {p}"),
            };
            bail!(
                "{} holds a sweep scan planned {by} (this gonio speaks protocol {PROTOCOL_VERSION}), whose positions may lie elsewhere; scan it again into a new directory",
                dir.display()
            );
        }
        Ok(plan)
    }
}
