//! Shared pieces of the test suites: proptest strategies for every message
//! type, and small hardware doubles for driving the firmware core without
//! the simulator.

pub mod chop_signal;
pub mod doubles;
pub mod strategies;
