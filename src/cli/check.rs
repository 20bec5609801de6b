//! `sweeptin check`: validate a mesh file.

use std::path::PathBuf;

/// Arguments of `sweeptin check`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to validate (.ply).
    pub mesh: PathBuf,
}

pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
