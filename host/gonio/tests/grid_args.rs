//! `--theta-i`, `--theta-o`, `--dphi`, the rings and `--for`, parsed as the
//! command line does and checked into the scan a head runs.

use anyhow::Result;
use clap::Parser;
use gonio::cli::grid::GridArgs;
use gonio_analysis::coefficients::Set;
use gonio_shared::ScanSpec;

#[derive(Debug, Parser)]
struct Grid {
    #[command(flatten)]
    grid: GridArgs,
}

fn grid(args: &[&str]) -> Result<ScanSpec> {
    let g = Grid::try_parse_from(std::iter::once("grid").chain(args.iter().copied()))?;
    g.grid.scan_spec()
}

fn refused(args: &[&str], why: &str) {
    let e = grid(args).expect_err(&format!("{args:?}")).to_string();
    assert!(e.contains(why), "{args:?}: {e}");
}

#[test]
fn default_grid_is_belcour() {
    assert_eq!(grid(&[]).unwrap(), ScanSpec::belcour_with_patterns());
    assert_eq!(
        grid(&["--theta-i", "15,30,60", "--theta-o", "0:90:3", "--dphi", "-180:180:10"]).unwrap(),
        ScanSpec::belcour_with_patterns()
    );
    assert_eq!(ScanSpec::belcour().len(), 3 * 31 * 37);
    assert_eq!(ScanSpec::belcour_with_patterns().len(), 3 * (31 * 37 + 400));
    assert_eq!(grid(&["--no-patterns"]).unwrap().patterns, None);
}

#[test]
fn bad_grids_are_refused_with_their_reason() {
    refused(&["--theta-o", "0:90"], "not START:STOP:STEP");
    refused(&["--theta-o", "0:90:3:1"], "not START:STOP:STEP");
    refused(&["--theta-o", "0:90:0"], "empty or malformed");
    refused(&["--dphi", "0:x:1"], "finite numbers");
    refused(&["--dphi", "0:inf:1"], "finite numbers");
    refused(&["--theta-i", "x"], "not a number");
    refused(&["--theta-i", "nan"], "not finite");
    refused(&["--theta-i", "1,2,3,4,5,6,7,8,9"], "at most 8");
    refused(&["--theta-i", "100"], "not an incidence");
    refused(&["--theta-i", "-10"], "not an incidence");
    refused(&["--theta-o", "0:95:5"], "beyond the view angles");
    refused(&["--theta-o", "-5:60:5"], "beyond the view angles");
    refused(&["--dphi", "200:400:10"], "beyond −360° to 360°");
    refused(&["--retro-rings", "40"], "radii in (0°");
    refused(&["--sweep", "--sweep-lobe", "0.001"], "the width must lie in");
    refused(
        &["--theta-o", "0:80:0.0001", "--no-patterns"],
        "3 incidences × (800001 θo × 37 Δφ + 0 pattern points) = 88800111 positions: more than the 10000000 a scan holds",
    );
}

/// Every value of both sets lies on a pattern point of the scan `--for`
/// makes, within what `gonio coefficients` calls measured.
#[test]
fn a_scan_for_the_standards_holds_every_geometry_they_name() {
    let spec = grid(&["--for", "astm-e810,en1436"]).unwrap();
    assert_eq!(spec.theta_i_deg.as_slice(), &[15.0, 30.0, 60.0, 4.0, 40.0, 45.0, 88.76]);
    let p = spec.patterns.as_ref().unwrap();
    assert_eq!(p.retro.radii_deg.len(), 11);
    let points: Vec<_> = (0..spec.len()).filter_map(|i| spec.point(i)).collect();
    for set in [Set::AstmE810, Set::En1436] {
        for r in set.requests() {
            let [ti, to, dp] = r.geometry.sample_angles_deg();
            let held = points.iter().any(|g| {
                (g.theta_i_deg as f64 - ti).abs() < 0.01
                    && (g.theta_o_deg as f64 - to).abs() < 0.01
                    && (g.dphi_deg.abs() as f64 - dp).abs() < 0.01
            });
            assert!(held, "{set:?}: ({ti}, {to}, {dp}) is not a point of the scan");
        }
    }
    refused(&["--for", "en1436", "--no-patterns"], "--no-patterns");
    refused(&["--for", "en1436", "--retro-azimuths", "7"], "even");
    refused(&["--for", "astm-e810", "--theta-i", "1,2,3,5,6"], "8 incidence");
}
