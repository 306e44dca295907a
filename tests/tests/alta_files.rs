//! ALTA files as ALTA writes and reads them. Every input
//! parametrization the reader knows is written here by an independent
//! computation from `(θi, θo, Δφ)` (the inverse of the reader's, from the
//! light and view vectors) and must read back as the same geometry; files
//! in the forms other tools write (CRLF, tabs, trailing blanks, comments
//! between rows, ALTA's ignored `#` lines, no `#PARAM_OUT`, no `#DIM`,
//! `#VS 1/2`) read as their clean form does; and random permutations of the
//! header with junk lines still give the same samples or an error that
//! names the line.

use gonio_analysis::fit::{Dataset, Units};
use gonio_analysis::formats::alta;
use proptest::prelude::*;
use std::f64::consts::PI;

type V3 = [f64; 3];

fn sph(t: f64, p: f64) -> V3 {
    [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()]
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Rotation about z by `a`, then about y by `b`, applied to `v` (the
/// inverse of ALTA's `Rz(φh)·Ry(θh)` is `Ry(−θh)·Rz(−φh)`).
fn rot_z(v: V3, a: f64) -> V3 {
    [a.cos() * v[0] - a.sin() * v[1], a.sin() * v[0] + a.cos() * v[1], v[2]]
}
fn rot_y(v: V3, a: f64) -> V3 {
    [a.cos() * v[0] + a.sin() * v[2], v[1], -a.sin() * v[0] + a.cos() * v[2]]
}

/// `(θh, φh, θd, φd)` of a light and a view, Rusin's half/difference angles
/// with ALTA's difference vector the view.
fn rusin(l: V3, v: V3) -> [f64; 4] {
    let s = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
    let n = dot(s, s).sqrt();
    let h = [s[0] / n, s[1] / n, s[2] / n];
    let (th, ph) = (h[2].acos(), h[1].atan2(h[0]));
    let d = rot_y(rot_z(v, -ph), -th);
    [th, ph, d[2].clamp(-1.0, 1.0).acos(), d[1].atan2(d[0])]
}

/// The rows of one parametrization for geometries `(θi, θo, Δφ)` (radians),
/// the light at azimuth `phi_l`.
fn rows(param: &str, geos: &[(f64, f64, f64)], phi_l: f64) -> Vec<Vec<f64>> {
    geos.iter()
        .map(|&(ti, to, dp)| {
            let (l, v) = (sph(ti, phi_l), sph(to, phi_l + dp));
            match param {
                "ISOTROPIC_TL_TV_PROJ_DPHI" => vec![ti, to * dp.cos(), to * dp.sin()],
                "ISOTROPIC_TV_TL_DPHI" => vec![to, ti, dp],
                "SPHERICAL_TL_PL_TV_PV" => vec![ti, phi_l, to, phi_l + dp],
                "RUSIN_TH_TD_PD" => {
                    // φh = 0: rotate the pair about the normal so that h has no azimuth.
                    let r = rusin(l, v);
                    let (l0, v0) = (rot_z(l, -r[1]), rot_z(v, -r[1]));
                    let r = rusin(l0, v0);
                    vec![r[0], r[2], r[3]]
                }
                "RUSIN_TH_PH_TD_PD" => rusin(l, v).to_vec(),
                "CARTESIAN" => vec![v[0], v[1], v[2], l[0], l[1], l[2]],
                other => panic!("no writer for {other}"),
            }
        })
        .collect()
}

fn file(param: &str, inputs: usize, body: &[Vec<f64>], values: &[f64]) -> String {
    let mut s = format!("#DIM {inputs} 1\n#PARAM_IN {param}\n#PARAM_OUT INV_STERADIAN\n");
    for (r, v) in body.iter().zip(values) {
        let cols: Vec<String> = r.iter().chain([v]).map(|x| format!("{x:e}")).collect();
        s.push_str(&cols.join(" "));
        s.push('\n');
    }
    s
}

fn geometries() -> Vec<(f64, f64, f64)> {
    let mut g = Vec::new();
    for ti in [0.0f64, 5.0, 30.0, 61.0, 85.0] {
        for to in [0.5f64, 12.0, 45.0, 80.0] {
            for dp in [0.0f64, 7.0, 90.0, 135.0, 179.0, -45.0] {
                g.push((ti.to_radians(), to.to_radians(), dp.to_radians()));
            }
        }
    }
    g
}

fn same_geometry(d: &Dataset, geos: &[(f64, f64, f64)], what: &str) {
    assert_eq!(d.observations.len(), geos.len(), "{what}");
    for (o, &(ti, to, dp)) in d.observations.iter().zip(geos) {
        assert!(
            (o.theta_i - ti).abs() < 1e-9 && (o.theta_o - to).abs() < 1e-9,
            "{what}: {o:?} vs {:?}",
            (ti, to, dp)
        );
        // Δφ is defined (up to its sign: isotropy) where neither direction is the normal.
        if ti > 1e-6 && to > 1e-6 {
            assert!((o.dphi.abs() - dp.abs()).abs() < 1e-9, "{what}: Δφ {} vs {}", o.dphi, dp);
        }
    }
}

#[test]
fn every_parametrization_reads_back_the_geometry_it_was_written_for() {
    let geos = geometries();
    let values: Vec<f64> = (0..geos.len()).map(|k| 0.1 + k as f64).collect();
    for (param, inputs) in [
        ("ISOTROPIC_TL_TV_PROJ_DPHI", 3),
        ("ISOTROPIC_TV_TL_DPHI", 3),
        ("SPHERICAL_TL_PL_TV_PV", 4),
        ("RUSIN_TH_TD_PD", 3),
        ("RUSIN_TH_PH_TD_PD", 4),
        ("CARTESIAN", 6),
    ] {
        for phi_l in [0.0, 1.1, -2.5] {
            if param.starts_with("ISOTROPIC") && phi_l != 0.0 {
                continue; // the light is at azimuth 0 by definition
            }
            let text = file(param, inputs, &rows(param, &geos, phi_l), &values);
            let d = alta::parse(&text).unwrap_or_else(|e| panic!("{param}: {e:#}"));
            same_geometry(&d, &geos, &format!("{param} (φL = {phi_l})"));
            assert_eq!(d.observations.iter().map(|o| o.value).collect::<Vec<_>>(), values);
            assert!(d.units_stated && d.warnings.is_empty(), "{param}: {:?}", d.warnings);
        }
    }
}

fn clean() -> String {
    let geos = geometries();
    let values: Vec<f64> = (0..geos.len()).map(|k| 1.0 + k as f64 * 0.01).collect();
    file(
        "ISOTROPIC_TL_TV_PROJ_DPHI",
        3,
        &rows("ISOTROPIC_TL_TV_PROJ_DPHI", &geos, 0.0),
        &values,
    )
}

#[test]
fn files_in_other_tools_forms_read_as_their_clean_form() {
    let reference = alta::parse(&clean()).unwrap();
    let text = clean();
    let (header, body) = text.split_at(text.find("#PARAM_OUT").unwrap());
    let body_lines: Vec<&str> = body.lines().skip(1).collect();
    // CRLF, tabs, trailing blanks, ALTA's own header lines, comments between rows.
    let mut messy = String::from("#ALTA HEADER DATA\r\n# a comment\r\n");
    messy.push_str(&header.replace('\n', " \t\r\n"));
    messy.push_str("#PARAM_OUT INV_STERADIAN  \r\n#VS 0\r\n#CMD measured elsewhere\r\n#ALTA END HEADER\r\n\r\n");
    for (k, l) in body_lines.iter().enumerate() {
        messy.push_str(&l.replace(' ', "\t"));
        messy.push_str(" \r\n");
        if k % 7 == 0 {
            messy.push_str("# between the rows\r\n   \r\n");
        }
    }
    let d = alta::parse(&messy).unwrap();
    assert_eq!(d.observations, reference.observations);

    // No #PARAM_OUT (ALTA's UNKNOWN_OUTPUT), no #DIM: read, and said so.
    let bare: String = text
        .lines()
        .filter(|l| !l.starts_with("#PARAM_OUT") && !l.starts_with("#DIM"))
        .map(|l| format!("{l}\n"))
        .collect();
    let d = alta::parse(&bare).unwrap();
    assert_eq!(d.observations, reference.observations);
    assert!(!d.units_stated);
    assert!(d.warnings.iter().any(|w| w.contains("#DIM")), "{:?}", d.warnings);

    // Several outputs (RGB): the first is used, with a warning.
    let rgb = text
        .replace("#DIM 3 1", "#DIM 3 3")
        .replace("#PARAM_OUT INV_STERADIAN", "#PARAM_OUT RGB_COLOR");
    let rgb: String = rgb
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                format!("{l}\n")
            } else {
                format!("{l} 7 8\n")
            }
        })
        .collect();
    let d = alta::parse(&rgb).unwrap();
    assert_eq!(d.observations, reference.observations);
    assert!(!d.units_stated && d.warnings.len() == 2, "{:?}", d.warnings);
}

#[test]
fn confidence_columns_become_uncertainties() {
    let text = "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n";
    let one = alta::parse(&format!("{text}#VS 1\n0.5 0.1 0.2 3.0 0.4\n")).unwrap();
    assert_eq!(one.observations[0].sigma, Some(0.2), "#VS 1: the half-width of a k = 2 interval");
    // ALTA's reader (`read_confidence_interval`): the interval [y − a, y + b].
    let two = alta::parse(&format!("{text}#VS 2\n0.5 0.1 0.2 3.0 0.3 0.5\n")).unwrap();
    assert!(
        (two.observations[0].sigma.unwrap() - 0.2).abs() < 1e-15,
        "#VS 2: how far below and above the value"
    );
    assert_eq!(two.units, Units::FrCos);
    // gonio's files from before it followed ALTA there: the ends, and a note that says so.
    let ends = alta::parse(&format!("{text}#VS 2\n# {}\n0.5 0.1 0.2 3.0 2.6 3.4\n", alta::ENDS_NOTE)).unwrap();
    assert!((ends.observations[0].sigma.unwrap() - 0.2).abs() < 1e-15, "older #VS 2: the ends");
    let rewritten = alta::write(&ends);
    assert!(!rewritten.contains(alta::ENDS_NOTE), "{rewritten}");
    let again = alta::parse(&rewritten).unwrap();
    assert!((again.observations[0].sigma.unwrap() - 0.2).abs() < 1e-15, "{rewritten}");
    for (bad, says) in [
        (
            format!("{text}#VS 2\n# {}\n0.5 0.1 0.2 3.0 3.4 2.6\n", alta::ENDS_NOTE),
            "line 6: the confidence interval is negative",
        ),
        (
            format!("{text}#VS 2\n0.5 0.1 0.2 3.0 -0.4 0.4\n"),
            "line 5: a confidence offset is negative",
        ),
        (
            format!("{text}#VS 1\n0.5 0.1 0.2 3.0 -0.4\n"),
            "line 5: the confidence half-width is negative",
        ),
        (
            format!("{text}#VS 2\n0.5 0.1 0.2 3.0 1e308 1e308\n"),
            "line 5: the confidence interval is wider than a number holds",
        ),
        (
            format!("{text}#VS 1\n0.5 0.1 0.2 3.0 1e308\n"),
            "line 5: the confidence interval is wider than a number holds",
        ),
        (
            format!("{text}#VS 2\n0.5 0.1 0.2 3.0 2.6\n"),
            "line 5: expected 6 numbers (3 inputs, 1 output, 2 confidence), found 5",
        ),
        (format!("{text}#VS 3\n"), "line 4: expected `#VS 0`, `#VS 1` or `#VS 2`"),
        (format!("{text}0.5 0.1 0.2 NaN\n"), "line 4: `NaN` is not a finite number"),
        (
            format!("{text}0.5 0.1 0.2 3\n#PARAM_IN CARTESIAN\n"),
            "line 5: #PARAM_IN after the data",
        ),
        (
            "#DIM 3 1\n#PARAM_IN STARK_2D\n".to_string(),
            "line 2: unsupported #PARAM_IN `STARK_2D`; supported:",
        ),
        (
            "#DIM 4 1\n#PARAM_IN ISOTROPIC_TV_TL_DPHI\n1 2 3 4 5\n".to_string(),
            "line 3: #DIM says 4 inputs but #PARAM_IN has 3",
        ),
    ] {
        let e = format!("{:#}", alta::parse(&bad).unwrap_err());
        assert!(e.contains(says), "`{e}` does not say `{says}`");
    }
}

/// Header lines (`#DIM`, `#PARAM_IN`, `#PARAM_OUT`, `#VS`) in any order,
/// with junk the way other tools leave it.
fn header_and_junk() -> impl Strategy<Value = (Vec<usize>, Vec<(usize, usize)>)> {
    (
        Just(vec![0usize, 1, 2, 3]).prop_shuffle(),
        proptest::collection::vec((0usize..60, 0usize..7), 0..12),
    )
}

const JUNK: [&str; 7] = [
    "",
    "   \t",
    "# comment",
    "#CMD gonio",
    "#ALTA HEADER DATA",
    "\r",
    "#  DIM 9 9 (a comment: space after #)",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]
    #[test]
    fn header_permutations_and_junk_lines_change_nothing((order, junk) in header_and_junk()) {
        let reference = alta::parse(&clean()).unwrap();
        let header = ["#DIM 3 1", "#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI", "#PARAM_OUT INV_STERADIAN", "#VS 0"];
        let mut lines: Vec<String> = order.iter().map(|&k| header[k].to_string()).collect();
        lines.extend(clean().lines().filter(|l| !l.starts_with('#')).map(str::to_string));
        // Junk at random places (index into the lines, counted from the top).
        for &(at, kind) in junk.iter().rev() {
            let at = at.min(lines.len());
            lines.insert(at, JUNK[kind].to_string());
        }
        let text = lines.join("\n");
        match alta::parse(&text) {
            Ok(d) => prop_assert_eq!(d.observations, reference.observations),
            Err(e) => {
                let e = format!("{e:#}");
                prop_assert!(e.starts_with("line "), "an error names the line: {}", e);
            }
        }
    }

    /// Random bytes in a valid file's rows: parsed, or refused with the line named; never a panic.
    #[test]
    fn damaged_rows_are_refused_with_their_line(k in 4usize..200, garbage in "[ -~]{0,12}") {
        let mut lines: Vec<String> = clean().lines().map(str::to_string).collect();
        let k = k.min(lines.len() - 1);
        lines[k] = garbage;
        if let Err(e) = alta::parse(&lines.join("\n")) {
            let e = format!("{e:#}");
            prop_assert!(e.starts_with("line ") || e.contains("no data lines"), "{}", e);
        }
    }
}

#[test]
fn a_full_turn_of_azimuth_is_the_same_geometry() {
    // Δφ written as 350° is −10°: the reader folds it, isotropy does the rest.
    let d = alta::parse("#DIM 3 1\n#PARAM_IN ISOTROPIC_TV_TL_DPHI\n#PARAM_OUT INV_STERADIAN\n0.3 0.4 6.1086523819801535 1\n").unwrap();
    assert!((d.observations[0].dphi.abs() - (2.0 * PI - 6.108_652_381_980_153_5)).abs() < 1e-12);
}
