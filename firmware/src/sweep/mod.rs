//! Measuring while moving. The head runs a sweep ([`run`], `Head::sweep`):
//! an ordinary move to its start, the detector ranged and settled there,
//! then one move to its end during which the chop runs on and every few
//! periods become a [`gonio_shared::SweptSample`], tagged from the step
//! timer's counts at its first period's start and its last one's end.
//! [`plan`] works out its speeds, a sweep scan's rows and the checks.

pub mod plan;
pub(crate) mod sweeping;
pub(crate) mod turns;

pub use plan::{check, check_path, limits, row_ends, row_levels, row_plan, row_speed, tag, RowPlan};
