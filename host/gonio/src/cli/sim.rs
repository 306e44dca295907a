//! `gonio sim`: a simulated head on a pseudo-terminal.

use super::material::SimHeadArgs;
use anyhow::Result;
use gonio_sim::serve_pty;
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct SimArgs {
    /// Path of the symbolic link to the head's terminal (pass it to `gonio scan --port`).
    #[arg(long, default_value = "/tmp/gonio-sim")]
    pub link: PathBuf,
    #[command(flatten)]
    pub sim_head: SimHeadArgs,
}

pub fn sim(a: SimArgs) -> Result<()> {
    serve_pty(a.sim_head.config()?, &a.link, |p| {
        // Stopped, it leaves no link behind that a later `--port` could
        // follow to a terminal someone else has opened since.
        gonio_acquire::interrupt::remove_on_exit(p.to_path_buf());
        eprintln!("simulated head listening on {} (Ctrl-C to stop)", p.display());
    })
}
