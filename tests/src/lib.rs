//! Shared pieces of the test suites, which the benchmarks (`bench/`) use
//! too: proptest strategies for every message type, hardware doubles for
//! driving the firmware core without the simulator, one scan read back, the
//! host model of the step-timer interrupt, the fixed-point models' cases,
//! sweeps on the simulated head with the true geometry their samples saw,
//! stops measured on the simulated head and the safety trials made of them,
//! and synthetic materials with their reference fits.

pub mod doubles;
pub mod fixed_agreement;
pub mod safety_trials;
pub mod scanning;
pub mod step_log;
pub mod stopping;
pub mod strategies;
pub mod sweeping;
pub mod synthetic;
