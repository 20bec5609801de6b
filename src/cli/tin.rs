//! `sweeptin tin`: points in, Delaunay TIN out.

use std::path::PathBuf;

/// Arguments of `sweeptin tin`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input points: XYZ text (`x y z` per line, comma or whitespace separated).
    pub input: PathBuf,
    /// Output mesh (.ply).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Which point survives among exact (x, y) duplicates.
    #[arg(long, value_enum, default_value_t = sweeptin::DuplicatePolicy::First)]
    pub duplicates: sweeptin::DuplicatePolicy,
}

pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
