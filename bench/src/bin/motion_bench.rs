//! `cargo run --release -p gonio-bench --bin motion-bench`: figures of the stage
//! control, as one JSON object on stdout (a table on stderr).
//!
//! - `ik_max_error_deg`: largest |FK(IK(g)) − g| over the reachable Belcour
//!   grid and 200 000 random reachable geometries (`ik_quantised_max_error_deg`:
//!   the same with the stage angles rounded to whole microsteps).
//! - `max_step_error_ticks`: largest distance, in 1 MHz timer ticks, between a
//!   STEP edge as the executor emits it and the analytical trapezoid, over
//!   moves of 1 to 160 000 microsteps on every axis at cruise and homing speeds.
//! - `max_step_rate_hz`: highest per-axis step rate, three axes stepping at
//!   once (at R, 0.91 R, 0.83 R), that the executor sustains on the host model
//!   of the interrupt when every interrupt takes `isr_cycles`: the worst
//!   handler `chip-bench` measured on the emulated Cortex-M4 (its
//!   `step_isr_instructions_max`, read from `target/chip-bench.json`; run it
//!   first), plus 24 cycles of exception entry and exit, one cycle per
//!   instruction at 168 MHz: every edge within one tick of its schedule, no
//!   step lost. Null when chip-bench has not run.
//! - `plan_time_s`, `raster_time_s`: the Belcour grid in the host's planned
//!   order (`scan-bench` compares it with its lower bound) and in raster order (θi, θo, Δφ loops, Δφ innermost), moves under
//!   the reference axis limits plus 50 ms settle and 100 ms integration per point.

use gonio_acquire::scan_order::{scan_time, visit_order};
use gonio_bench::chip_costs::{self, EXCEPTION_CYCLES};
use gonio_firmware::config::{HeadConfig, REFERENCE};
use gonio_firmware::hw::StepBlock;
use gonio_firmware::kinematics;
use gonio_firmware::motion::blocks::profile_blocks;
use gonio_firmware::motion::{target_steps, trapezoid, Position, PARK};
use gonio_firmware::units;
use gonio_shared::{Axis, Geometry, ScanSpec};
use gonio_tests::step_log::{executor, run, Scope};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::time::Instant;

const TICK_HZ: u32 = 1_000_000;

/// The worst step interrupt chip-bench measured, in cycles (see the header).
fn measured_isr_cycles() -> Option<u64> {
    let text = std::fs::read_to_string(chip_costs::report_path()).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some(v["step_isr_instructions_max"].as_u64()? + EXCEPTION_CYCLES)
}

/// Distance (degrees) between two geometries in their frame-invariant terms:
/// θi, θo and the angle ψ between light and view (Δφ alone is meaningless
/// where θi or θo vanishes: every Δφ is then the same configuration).
fn geometry_error(a: &Geometry, b: &Geometry) -> f64 {
    let psi = |g: &Geometry| {
        let (ti, to, dp) = (
            (g.theta_i_deg as f64).to_radians(),
            (g.theta_o_deg as f64).to_radians(),
            (g.dphi_deg as f64).to_radians(),
        );
        let l = [ti.sin(), 0.0, ti.cos()];
        let v = [to.sin() * dp.cos(), to.sin() * dp.sin(), to.cos()];
        let cross = [l[1] * v[2] - l[2] * v[1], l[2] * v[0] - l[0] * v[2], l[0] * v[1] - l[1] * v[0]];
        let sin = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
        sin.atan2(l[0] * v[0] + l[1] * v[1] + l[2] * v[2]).to_degrees()
    };
    let d = |x: f32, y: f32| (x as f64 - y as f64).abs();
    d(a.theta_i_deg, b.theta_i_deg)
        .max(d(a.theta_o_deg, b.theta_o_deg))
        .max((psi(a) - psi(b)).abs())
}

fn ik_errors(cfg: &HeadConfig) -> (f64, f64, usize) {
    let mut rng = StdRng::seed_from_u64(4);
    let belcour = ScanSpec::belcour();
    let mut geos: Vec<Geometry> = (0..belcour.len()).filter_map(|i| belcour.point(i)).collect();
    geos.extend((0..200_000).map(|_| {
        Geometry::new(
            rng.random_range(0.0..89.0),
            rng.random_range(0.0..89.0),
            rng.random_range(-180.0..180.0),
        )
    }));
    let (mut exact, mut quantised, mut n) = (0.0f64, 0.0f64, 0);
    for g in geos {
        let Ok(axes) = kinematics::inverse(cfg, &g) else { continue };
        n += 1;
        exact = exact.max(geometry_error(&kinematics::forward(&axes), &g));
        let pos = Position {
            steps: target_steps(cfg, &axes),
            homed: [true; 3],
            in_flight: None,
        };
        quantised = quantised.max(geometry_error(&kinematics::forward(&pos.angles(cfg)), &g));
    }
    (exact, quantised, n)
}

fn max_step_error(cfg: &HeadConfig) -> (f64, u64) {
    let pulse = units::step_pulse_ticks(&cfg.driver, TICK_HZ);
    let (mut worst, mut steps) = (0.0f64, 0u64);
    for axis in Axis::ALL {
        let c = cfg.axis(axis);
        for dps in [c.max_speed_dps, c.home_slow_dps] {
            for n in [1u32, 2, 3, 5, 17, 100, 1_000, 10_000, 40_000, 160_000] {
                let t = trapezoid(c, n, dps);
                let scope = Scope::default();
                let mut exec = executor(&scope, pulse);
                assert!(profile_blocks(&t, TICK_HZ, |b| exec.push(axis, b).is_ok()), "queue too short");
                run(&mut exec, &scope, 0, 1, 0);
                let e = scope.rises("step", axis.index());
                assert_eq!(e.len(), n as usize);
                for (k, tick) in e.iter().enumerate() {
                    worst = worst.max((*tick as f64 - t.step_time(k as u32 + 1) * TICK_HZ as f64).abs());
                }
                steps += n as u64;
            }
        }
    }
    (worst, steps)
}

/// Three axes at constant rates R, 0.91 R, 0.83 R for 20 ms; the largest
/// edge delay (ticks) and steps lost, with `isr_ticks` of service time.
fn rate_trial(rate: f64, isr_ticks: u64, pulse: u64) -> (f64, u32, u64, f64) {
    let scope = Scope::default();
    let mut exec = executor(&scope, pulse);
    let mut want: Vec<Vec<f64>> = Vec::new();
    for (i, f) in [1.0, 0.91, 0.83].iter().enumerate() {
        let period = TICK_HZ as f64 / (rate * f);
        let count = (0.02 * rate * f) as u32;
        let b = StepBlock {
            interval: (period * 4_294_967_296.0).round() as u64,
            count,
            add: 0,
        };
        exec.push(Axis::ALL[i], b).expect("queue");
        want.push((1..=count).map(|k| (k as f64 * period).round()).collect());
    }
    let t0 = Instant::now();
    let fires = run(&mut exec, &scope, 0, 1, isr_ticks);
    let ns_per_fire = t0.elapsed().as_nanos() as f64 / fires as f64;
    let mut delay = 0.0f64;
    for (axis, want) in want.iter().enumerate() {
        for (tick, w) in scope.rises("step", axis).iter().zip(want) {
            delay = delay.max(*tick as f64 - w);
        }
    }
    (delay, exec.collisions(), fires, ns_per_fire)
}

fn main() {
    let cfg = REFERENCE;
    let (ik, ik_q, ik_points) = ik_errors(&cfg);
    let finest_microstep = cfg
        .axes
        .iter()
        .map(|a| 360.0 / a.microsteps_per_rev as f64)
        .fold(f64::MAX, f64::min);
    let (step_err, steps_checked) = max_step_error(&cfg);

    let pulse = units::step_pulse_ticks(&cfg.driver, TICK_HZ);
    let isr_cycles = measured_isr_cycles();
    if isr_cycles.is_none() {
        eprintln!("no target/chip-bench.json: run chip-bench first for the step rate");
    }
    let isr_ticks = isr_cycles.map_or(0, |c| (c * TICK_HZ as u64).div_ceil(168_000_000));
    let mut max_rate = 0.0;
    let mut host_ns = 0.0;
    let mut r = 5_000.0;
    while isr_cycles.is_some() && r <= 400_000.0 {
        let (delay, lost, _, ns) = rate_trial(r, isr_ticks, pulse);
        if delay <= 1.0 && lost == 0 {
            max_rate = r;
            host_ns = ns;
        } else {
            break;
        }
        r *= 1.05;
    }

    let spec = ScanSpec::belcour();
    let plan = scan_time(&cfg, &spec, visit_order(&cfg, &spec, PARK), PARK, 0.05, 0.1);
    let raster = scan_time(&cfg, &spec, 0..spec.len(), PARK, 0.05, 0.1);
    let serpentine = scan_time(&cfg, &spec, (0..spec.len()).filter_map(|o| spec.index_at_order(o)), PARK, 0.05, 0.1);

    let out = serde_json::json!({
        "ik_max_error_deg": ik,
        "ik_quantised_max_error_deg": ik_q,
        "ik_points": ik_points,
        "microstep_deg": finest_microstep,
        "max_step_error_ticks": step_err,
        "steps_checked": steps_checked,
        "max_step_rate_hz": isr_cycles.map(|_| max_rate),
        "isr_cycles": isr_cycles,
        "host_ns_per_interrupt": host_ns,
        "plan_time_s": plan.total_s(),
        "raster_time_s": raster.total_s(),
        "plan_moves_s": plan.moves_s,
        "raster_moves_s": raster.moves_s,
        "measured_points": plan.measured,
        "plan_over_raster": plan.total_s() / raster.total_s(),
        "serpentine_time_s": serpentine.total_s(),
    });
    eprintln!(
        "motion benchmark (reference axes: {:?} deg/s, {:?} deg/s²)",
        cfg.axes.map(|a| a.max_speed_dps),
        cfg.axes.map(|a| a.max_accel_dps2)
    );
    eprintln!("  IK round trip     {ik:.2e}° exact, {ik_q:.2e}° with microstep rounding, over {ik_points} geometries (microstep {finest_microstep:.2e}°)");
    eprintln!("  step timing       {step_err:.3} ticks worst over {steps_checked} steps (≤ 1)");
    eprintln!("  step rate         {max_rate:.0} Hz per axis, three axes, {isr_cycles:?} cycles per interrupt (≥ 50 000)");
    eprintln!(
        "  Belcour grid      planned {:.0} s vs raster {:.0} s (moves {:.0} s vs {:.0} s), ratio {:.3} (≤ 0.75); plain serpentine {:.0} s",
        plan.total_s(),
        raster.total_s(),
        plan.moves_s,
        raster.moves_s,
        plan.total_s() / raster.total_s(),
        serpentine.total_s()
    );
    println!("{out}");
}
