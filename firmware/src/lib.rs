//! The head's firmware core: everything the STM32F405 runs, except the wiring
//! of peripherals, which lives in the `gonio-head` binary.
//!
//! The core is generic over `embedded-hal` pins and delays and over three
//! small traits of its own ([`hw::AdcStream`], [`hw::StepTimer`],
//! [`hw::Clock`]), so the same code runs on the chip, against
//! `embedded-hal-mock` in tests, and on virtual hardware in the simulated head.
//! Signal processing ([`demod`]) and motion planning ([`motion`]) know nothing
//! of the hardware; [`units`] is the one place where SI units become ticks,
//! steps and codes.
#![cfg_attr(not(test), no_std)]
// The core's futures run on single-threaded executors (embassy's, or a
// blocking one in the simulated head); no `Send` bound is wanted.
#![allow(async_fn_in_trait)]

pub mod log;

pub mod active_scan;
pub mod config;
mod conversation;
pub mod crystal;
pub mod demod;
pub mod detector;
pub mod dispatch;
pub mod footprint;
pub mod guard;
pub mod head;
pub mod homing;
pub mod hw;
pub mod kinematics;
pub mod link;
pub mod math;
pub mod motion;
pub mod restart;
pub mod sanity;
mod serve;
pub mod state;
pub mod sweep;
pub mod units;

pub use head::Head;
