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
fn the_defaults_hold_a_narrow_retro_lobe_and_the_glass_beads_within_tolerance() {
    let tape = narrow_tape();
    let beads = GlassBeads::default();
    type Brdf<'a> = &'a dyn Fn(&Directions) -> f64;
    let cases: [(&str, Brdf); 2] = [("narrow tape", &|d| tape.eval(d)), ("glass beads", &|d| beads.eval(d))];
    for (name, f) in cases {
        let table = Table::new(f, name, &Options::default()).unwrap();
        let a = accuracy(&table, f, 4000, 3f64.to_radians());
        assert!(a.within_tolerance(), "{name}: {a:?}");
    }
}

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
    // A spectral file: an `rgb` field would make Mitsuba read it as RGB.
    assert!(fields.iter().all(|f| f.name != "rgb"));
    let theta = fields.iter().find(|f| f.name == "theta_i").unwrap().as_f32().unwrap();
    assert!(theta.windows(2).all(|w| w[0] < w[1]) && theta[0] == 0.0);
}
