//! `sweeptin check`: validate a mesh file.

use anyhow::Context;
use std::path::PathBuf;

/// Arguments of `sweeptin check`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to validate (.ply: ASCII or binary, triangles only).
    pub mesh: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let (vertices, triangles) = sweeptin::io::read_ply(&args.mesh)?;
    sweeptin::validate::validate(&vertices, &triangles).with_context(|| {
        format!(
            "{} is not valid ({} vertices, {} triangles)",
            args.mesh.display(),
            vertices.len(),
            triangles.len()
        )
    })?;
    println!(
        "{}: valid ({} vertices, {} triangles)",
        args.mesh.display(),
        vertices.len(),
        triangles.len()
    );
    Ok(())
}
