//! Shared pieces of the test suites and benchmarks: proptest strategies for
//! every message type, hardware doubles for driving the firmware core without
//! the simulator, one scan read back, the host model of the step-timer
//! interrupt, the chopped signal of the lock-in benchmark, and the
//! fixed-point models' cases, sweeps on the simulated head with the
//! true geometry their samples saw, and the virtual board's runs: its
//! fault trials and the scans a fault strikes.

pub mod board_faults;
pub mod board_scans;
pub mod chip_costs;
pub mod chop_signal;
pub mod doubles;
pub mod fixed_agreement;
pub mod safety_bench;
pub mod scanning;
pub mod step_log;
pub mod stops;
pub mod strategies;
pub mod sweeping;
pub mod synthetic;
pub mod virtual_board;
