//! The fitting engine on synthetic data (`gonio_tests::synthetic`): recovery
//! of known parameters, every model on data from itself, the global search
//! without starting points, weights, units, and the ALTA round trip.

use gonio_analysis::fit::goodness::Goodness;
use gonio_analysis::fit::{self, Dataset, FitSpec, Units, Weighting};
use gonio_analysis::formats::alta;
use gonio_brdf::{ModelId, Param};
use gonio_tests::synthetic;

/// Retro-phong's parameters within 5 % (or 2 standard errors) of
/// the truth, from 7 000 samples with 2 % noise, no starting point, weighted
/// by each sample's uncertainty. Ten noise seeds: a 2σ band misses one
/// draw in twenty, so each parameter may miss once; the standard errors are
/// checked too (the mean |z| of a calibrated error is 0.8).
#[test]
fn retro_phong_parameters_are_recovered_from_noisy_data() {
    let truth = synthetic::reference(ModelId::RetroPhong);
    let names = ModelId::RetroPhong.param_names();
    let (mut misses, mut z_sum) = (vec![0; names.len()], vec![0.0; names.len()]);
    let seeds = 10;
    for seed in 1..=seeds {
        let data = synthetic::samples(&truth, 7000, 0.02, seed);
        let f = fit::fit(
            &data,
            &FitSpec {
                weighting: Weighting::Sigma,
                ..FitSpec::new(ModelId::RetroPhong)
            },
        )
        .unwrap();
        for i in 0..names.len() {
            let (got, want) = (f.material.params[i], truth.params[i]);
            let se = f.stderr[i].expect("a standard error for every free parameter");
            z_sum[i] += ((got - want) / se).abs();
            if (got - want).abs() > 0.05 * want.abs() && (got - want).abs() > 2.0 * se {
                misses[i] += 1;
            }
        }
    }
    for (i, name) in names.iter().enumerate() {
        let mean_z = z_sum[i] / seeds as f64;
        assert!(misses[i] <= 1, "{name}: outside 5 % and 2σ in {} of {seeds} seeds", misses[i]);
        assert!(
            (0.4..1.4).contains(&mean_z),
            "{name}: mean |z| {mean_z}: standard errors not calibrated"
        );
    }
}

/// A right model fitted with right σ draws its reduced χ² from the χ²
/// distribution: inside its 99 % interval in at least 98 % of trials
/// (500 samples, 2 % noise), for a one-parameter model and a six-parameter
/// lobe; and the fit says so with a p-value above 1 %, mostly.
#[test]
fn reduced_chi2_of_right_fits_lies_in_its_interval() {
    for (model, trials) in [(ModelId::Lambert, 200u64), (ModelId::RetroPhong, 50)] {
        let truth = synthetic::reference(model);
        let spec = FitSpec {
            weighting: Weighting::Sigma,
            ..FitSpec::new(model)
        };
        let (mut inside, mut p_low) = (0, 0);
        for seed in 1..=trials {
            let data = synthetic::samples(&truth, 500, 0.02, 100 + seed);
            let g = fit::fit(&data, &spec).unwrap().goodness.expect("χ² of a σ-weighted fit");
            assert_eq!(g.dof, 500 - model.param_names().len());
            let (lo, hi) = Goodness::interval(g.dof, 0.99);
            inside += (lo..=hi).contains(&g.reduced_chi2) as u64;
            p_low += (g.p_value < 0.01) as u64;
        }
        assert!(inside * 100 >= 98 * trials, "{}: {inside} of {trials} inside", model.name());
        assert!(p_low * 100 <= 3 * trials, "{}: p < 0.01 in {p_low} of {trials}", model.name());
    }
    // The wrong model on the same data: far outside, p ≈ 0.
    let data = synthetic::samples(&synthetic::reference(ModelId::RetroPhong), 500, 0.02, 7);
    let g = fit::fit(
        &data,
        &FitSpec {
            weighting: Weighting::Sigma,
            ..FitSpec::new(ModelId::Lambert)
        },
    )
    .unwrap()
    .goodness
    .unwrap();
    assert!(g.reduced_chi2 > 10.0 && g.p_value < 1e-12, "{g:?}");
}

/// Lobes whose amplitudes lie beyond their default box (abc-retro's A_b
/// and A_r at 521 and 553, as a measured tape's are, the box's edge at
/// 100): the fit widens the boxes, says so, and finds them; a box the user
/// gave stays, and the parameter on its edge is named.
#[test]
fn a_default_box_widens_where_the_optimum_lies_beyond_it() {
    let mut truth = synthetic::reference(ModelId::AbcRetro);
    // Narrow lobes (B = 3 000, C = 2), so that the data's median, which
    // scales the amplitudes' boxes, stays the diffuse level.
    truth.params[2..5].copy_from_slice(&[521.0, 3000.0, 2.0]);
    truth.params[5..8].copy_from_slice(&[553.0, 3000.0, 2.0]);
    let data = synthetic::samples(&truth, 3000, 0.01, 5);
    let spec = FitSpec {
        weighting: Weighting::Sigma,
        ..FitSpec::new(ModelId::AbcRetro)
    };
    let f = fit::fit(&data, &spec).unwrap();
    let widened: Vec<&str> = f.widened.iter().map(|w| w.0).collect();
    assert!(
        widened.contains(&"ab") && widened.contains(&"ar"),
        "{widened:?} {:?} {:?}",
        f.material.params,
        f.at_bound
    );
    assert!(f.at_bound.is_empty(), "still on a bound: {:?}", f.at_bound);
    for i in [2, 5] {
        let (got, want) = (f.material.params[i], truth.params[i]);
        assert!((got / want - 1.0).abs() < 0.05, "param {i}: {got} vs {want}");
    }
    let boxed = fit::fit(
        &data,
        &FitSpec {
            bounds: vec![(2, 0.0, 100.0)],
            ..spec
        },
    )
    .unwrap();
    assert!(boxed.at_bound.contains(&"ab") && !boxed.widened.iter().any(|w| w.0 == "ab"));
    assert!(boxed.metrics.rmse > f.metrics.rmse);
}

/// Every model reaches NCC ≥ 0.99 on noise-free data generated from itself,
/// found by the global search alone, in both retro parametrizations.
#[test]
fn every_model_fits_data_from_itself() {
    for model in ModelId::ALL {
        let params = if model.has_retro_cosine() {
            vec![Param::View, Param::Back]
        } else {
            vec![Param::View]
        };
        for param in params {
            let mut truth = synthetic::reference(model);
            truth.param = param;
            let data = synthetic::samples(&truth, 3240, 0.0, 1);
            let f = fit::fit(
                &data,
                &FitSpec {
                    param,
                    ..FitSpec::new(model)
                },
            )
            .unwrap();
            assert!(f.metrics.ncc >= 0.99, "{} {param:?}: ncc {}", model.name(), f.metrics.ncc);
            assert!(f.metrics.nrmse < 1e-3, "{} {param:?}: nrmse {}", model.name(), f.metrics.nrmse);
        }
    }
}

/// Without a starting point the search reaches the optimum the local fit
/// finds from the truth, for several seeds (`fit-bench` runs 20 per model).
#[test]
fn the_global_search_needs_no_starting_point() {
    for model in ModelId::ALL {
        let truth = synthetic::reference(model);
        let data = synthetic::samples(&truth, 3000, 0.02, 5);
        let spec = FitSpec::new(model);
        let reference = fit::fit(
            &data,
            &FitSpec {
                start: Some(truth.params.clone()),
                ..spec.clone()
            },
        )
        .unwrap()
        .cost;
        for seed in 1..=3 {
            let c = fit::fit(&data, &FitSpec { seed, ..spec.clone() }).unwrap().cost;
            assert!(
                c <= reference * (1.0 + 1e-6),
                "{} seed {seed}: cost {c} vs {reference}",
                model.name()
            );
        }
    }
}

#[test]
fn fitting_units_and_weights_reach_the_same_noise_free_optimum() {
    let truth = synthetic::reference(ModelId::BeckmannRetro);
    let data = synthetic::samples(&truth, 2000, 0.0, 3);
    let cos_data = data.in_units(Units::FrCos).unwrap();
    for (d, units, weighting) in [
        (&data, Units::FrCos, Weighting::Relative),
        (&cos_data, Units::Fr, Weighting::Uniform),
        (&cos_data, Units::FrCos, Weighting::Uniform),
    ] {
        let f = fit::fit(
            d,
            &FitSpec {
                units,
                weighting,
                ..FitSpec::new(ModelId::BeckmannRetro)
            },
        )
        .unwrap();
        for (got, want) in f.material.params.iter().zip(&truth.params) {
            assert!((got - want).abs() <= 1e-6 * want.abs(), "{units:?} {weighting:?}: {got} vs {want}");
        }
    }
    // Sigma weights need an uncertainty on every sample.
    let mut no_sigma = data.clone();
    no_sigma.observations[7].sigma = None;
    let e = fit::fit(
        &no_sigma,
        &FitSpec {
            weighting: Weighting::Sigma,
            ..FitSpec::new(ModelId::Lambert)
        },
    )
    .unwrap_err();
    assert!(format!("{e:#}").contains("sample 8 has none"), "{e:#}");
}

/// ALTA export → import reproduces every value to 1e-12 relative
/// (in fact exactly: numbers are written in their shortest round-trip form).
#[test]
fn alta_round_trip_is_exact() {
    let truth = synthetic::reference(ModelId::AbcRetro);
    for units in [Units::Fr, Units::FrCos] {
        let data: Dataset = synthetic::samples(&truth, 3240, 0.02, 9).in_units(units).unwrap();
        let back = alta::parse(&alta::write(&data)).unwrap();
        assert_eq!(back.units, units);
        assert_eq!(back.observations.len(), data.observations.len());
        for (a, b) in data.observations.iter().zip(&back.observations) {
            assert_eq!(a.value, b.value);
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(1.0);
            // Angles come back through (θV cosΔφ, θV sinΔφ): same direction to 1e-12.
            assert!(close(a.theta_i, b.theta_i) && close(a.theta_o, b.theta_o));
            assert!(a.theta_o < 1e-12 || close(a.dphi.sin(), b.dphi.sin()) && close(a.dphi.cos(), b.dphi.cos()));
        }
    }
}

/// An input every sample shares (a reference plate 1 % off, a
/// stage zero) does not average out over the samples. The covariance adds
/// the move of the optimum it causes: refitting data shifted by exactly that
/// input's effect moves each parameter by the square root of what it added
/// to the diagonal, and a 1 % scale gives retro-phong's linear parameters
/// 1 % and its exponents nothing.
#[test]
fn shared_inputs_enter_the_covariance_as_the_refit_moves_the_parameters() {
    let truth = synthetic::reference(ModelId::RetroPhong);
    let plain = synthetic::samples(&truth, 3000, 0.02, 4);
    let mut shared = plain.clone();
    for o in &mut shared.observations {
        o.shared[0] = 0.01 * o.value;
    }
    let spec = FitSpec {
        weighting: Weighting::Sigma,
        ..FitSpec::new(ModelId::RetroPhong)
    };
    let (a, b) = (fit::fit(&plain, &spec).unwrap(), fit::fit(&shared, &spec).unwrap());
    assert_eq!(
        a.material.params, b.material.params,
        "the shifts change the covariance, not the fit"
    );
    let mut moved = shared.clone();
    for o in &mut moved.observations {
        o.value += o.shared[0];
    }
    let start = FitSpec {
        start: Some(a.material.params.clone()),
        ..spec
    };
    let c = fit::fit(&moved, &start).unwrap();
    let (ca, cb) = (a.covariance.unwrap(), b.covariance.unwrap());
    for (i, name) in ModelId::RetroPhong.param_names().iter().enumerate() {
        let predicted = (cb[(i, i)] - ca[(i, i)]).max(0.0).sqrt();
        let refit = (c.material.params[i] - a.material.params[i]).abs();
        let p = a.material.params[i].abs();
        assert!(
            (refit - predicted).abs() <= 0.05 * predicted + 1e-6 * p,
            "{name}: refit moved {refit:.3e}, the covariance says {predicted:.3e}"
        );
        let linear = ["kd", "k1", "k2", "k3"].contains(name);
        let want = if linear { 0.01 * p } else { 0.0 };
        assert!((predicted - want).abs() <= 1e-3 * p, "{name}: {predicted:.3e} vs {want:.3e}");
    }
}

/// The samples and the search's candidates are shared among threads, but
/// the sums stay in task order and the candidates in theirs: one thread
/// and three give the very same fit, bit for bit (the sample count is past
/// the size the evaluation is split at).
#[test]
fn a_fit_does_not_depend_on_the_number_of_threads() {
    for model in [ModelId::AbcRetro, ModelId::Lafortune] {
        let data = synthetic::samples(&synthetic::reference(model), 3000, 0.02, 9);
        let spec = FitSpec::new(model);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| fit::fit(&data, &spec).unwrap())
        };
        let (one, three) = (on(1), on(3));
        assert_eq!(one.material.params, three.material.params, "{}", model.name());
        assert_eq!(one.cost.to_bits(), three.cost.to_bits(), "{}", model.name());
    }
}
