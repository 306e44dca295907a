//! The `gonio` tool: [`cli`] parses the command line and calls acquisition
//! (`gonio-acquire`: talk to a head, scan into a directory) and analysis
//! (`gonio-analysis`: calibrate, fit, report), which meet only in the scan
//! directory's files (`gonio-scan-dir`). It is also where the simulated head
//! (`gonio-sim`) is plugged in as a target ([`cli::in_process`]).

pub mod cli;
