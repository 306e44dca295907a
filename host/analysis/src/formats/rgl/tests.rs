use super::*;
use gonio_brdf::{GlassBeads, Material, ModelId, Param};

/// A retroreflective tape whose retro and mirror lobes are both `cos^1000`
/// (about 1.8° wide): the narrow lobe the defaults are sized for.
fn narrow_tape() -> Material {
    Material {
        model: ModelId::RetroPhong,
        params: vec![0.05, 1000.0, 0.8, 0.1, 0.02, 3.0],
        param: Param::View,
    }
}

fn lambert() -> Material {
    Material {
        model: ModelId::Lambert,
        params: vec![0.5],
        param: Param::View,
    }
}

#[test]
fn the_defaults_hold_a_narrow_retro_lobe_and_finer_slices_the_glass_beads_ring() {
    let tape = narrow_tape();
    let f = |d: &Directions| tape.eval(d);
    let a = accuracy(&Table::new(&f, "tape", &Options::default()).unwrap(), &f, 4000, 3f64.to_radians());
    assert!(a.within_tolerance(), "narrow tape: {a:?}");
    // The beads' 0.6° ring, between slices 0.5° apart, is filled in.
    let beads = GlassBeads::default();
    let f = |d: &Directions| beads.eval(d);
    let a = accuracy(&Table::new(&f, "beads", &Options::default()).unwrap(), &f, 4000, 3f64.to_radians());
    assert!(!a.within_tolerance() && a.retro_peak > 0.05, "glass beads at the defaults: {a:?}");
    let fine = Options {
        theta_i_step_deg: BEADS_STEP_DEG,
        ..Options::default()
    };
    let a = accuracy(&Table::new(&f, "beads", &fine).unwrap(), &f, 4000, 3f64.to_radians());
    assert!(a.within_tolerance(), "glass beads at {BEADS_STEP_DEG}°: {a:?}");
}

/// The incidence step that holds the glass beads (docs/render.md).
const BEADS_STEP_DEG: f64 = 0.125;

#[test]
fn a_coarse_table_is_measured_as_such() {
    let tape = narrow_tape();
    let f = |d: &Directions| tape.eval(d);
    let coarse = Options {
        spectra: 9,
        vndf: 9,
        theta_i_step_deg: 10.0,
        ..Options::default()
    };
    let a = accuracy(&Table::new(&f, "coarse", &coarse).unwrap(), &f, 2000, 3f64.to_radians());
    assert!(!a.within_tolerance(), "{a:?}");
}

#[test]
fn a_lambertian_surface_comes_back_flat() {
    let m = lambert();
    let f = |d: &Directions| m.eval(d);
    let table = Table::new(&f, "lambert", &Options::default()).unwrap();
    for (ti, to, dphi) in [(0.0, 30.0, 0.0), (30.0, 30.0, 0.0), (45.0, 60.0, 120.0), (70.0, 10.0, 180.0)] {
        let d = Directions::from_degrees(to, ti, dphi);
        let got = table.eval(d.v, d.l) / d.l[2];
        assert!((got / (0.5 / PI) - 1.0).abs() < 2e-3, "({ti}, {to}, {dphi}): {got}");
    }
}

#[test]
fn values_that_are_not_a_brdf_are_refused_with_their_geometry() {
    let nan = |d: &Directions| if d.cos_o() < 0.5 { f64::NAN } else { 0.1 };
    let e = Table::new(&nan, "nan", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("NaN") && e.contains("θ = "), "{e}");
    let nan_off_retro = |d: &Directions| if d.cos_o() < 0.5 && d.cos_i() > 0.9 { f64::NAN } else { 0.1 };
    let e = Table::new(&nan_off_retro, "nan", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("NaN") && e.contains("θo"), "{e}");
    let e = Table::new(&|_: &Directions| 0.0, "black", &Options::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no retroreflection"), "{e}");
    for bad in [
        Options {
            spectra: 100_000,
            ..Options::default()
        },
        Options {
            theta_i_step_deg: 0.001,
            ..Options::default()
        },
    ] {
        assert!(Table::new(&|_: &Directions| 0.1, "x", &bad).is_err());
    }
    let negative = |d: &Directions| 0.1 - d.cos_i() * d.cos_o();
    let e = Table::new(&negative, "negative", &Options::default()).unwrap_err().to_string();
    assert!(e.contains("cannot tabulate"), "{e}");
}

#[test]
fn the_file_has_the_fields_and_shapes_the_measured_plugin_checks() {
    let m = lambert();
    let f = |d: &Directions| m.eval(d);
    let opt = Options {
        spectrum: Spectrum::Visible,
        ..Options::default()
    };
    let table = Table::new(&f, "lambert, grey", &opt).unwrap();
    let fields = tensor::read(&table.bytes()).unwrap();
    let shape = |name: &str| {
        fields
            .iter()
            .find(|f| f.name == name)
            .unwrap_or_else(|| panic!("{name}"))
            .shape
            .clone()
    };
    let (nt, s, v, n) = (table.theta_i().len(), opt.spectra, opt.vndf, opt.ndf);
    assert_eq!(shape("theta_i"), [nt]);
    assert_eq!(shape("phi_i"), [1]);
    assert_eq!(shape("wavelengths"), [2]);
    assert_eq!(shape("ndf"), [n, n]);
    assert_eq!(shape("sigma"), [n, n]);
    assert_eq!(shape("vndf"), [1, nt, v, v]);
    assert_eq!(shape("luminance"), [1, nt, s, s]);
    assert_eq!(shape("spectra"), [1, nt, 2, s, s]);
    assert_eq!(shape("jacobian"), [1]);
    assert_eq!(shape("description"), ["lambert, grey".len()]);
    // A spectral file: its values as spectra at wavelengths, no RGB table.
    assert!(fields.iter().all(|f| f.name != "rgb"));
    let theta = fields.iter().find(|f| f.name == "theta_i").unwrap().as_f32().unwrap();
    assert!(theta.windows(2).all(|w| w[0] < w[1]) && theta[0] == 0.0);
    // An RGB file: the same values three times, no wavelengths.
    let rgb = Table::new(
        &f,
        "lambert, rgb",
        &Options {
            spectrum: Spectrum::Rgb,
            ..Options::default()
        },
    )
    .unwrap();
    let fields = tensor::read(&rgb.bytes()).unwrap();
    let rgb_field = fields.iter().find(|f| f.name == "rgb").unwrap();
    assert_eq!(rgb_field.shape, [1, nt, 3, s, s]);
    assert!(fields.iter().all(|f| f.name != "wavelengths" && f.name != "spectra"));
    // Every step stays distinct in f32, whatever the step.
    for step in [0.4170616104265403, 0.05, 1.0, 7.0] {
        let t: Vec<f32> = incidences(step).iter().map(|&x| x as f32).collect();
        assert!(t.windows(2).all(|w| w[0] < w[1]), "step {step}");
        assert_eq!(*t.last().unwrap(), THETA_I_MAX_DEG.to_radians() as f32);
    }
}
