//! `sweeptin check`: validate a mesh file.

use anyhow::Context;
use std::path::PathBuf;
use sweeptin::breaklines::{CleanOptions, read_files};
use sweeptin::validate::{CdtCheck, validate_cdt_with};

/// Arguments of `sweeptin check`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The mesh to validate (.ply: ASCII or binary, triangles only).
    pub mesh: PathBuf,
    /// The breaklines the mesh was made with (repeatable; also the --boundary and --holes files):
    /// every segment must be made of mesh edges, and only edges off the segments must be Delaunay.
    #[arg(long = "breaklines", value_name = "FILE")]
    pub breaklines: Vec<PathBuf>,
    /// The mesh was trimmed (--boundary, --holes, --max-edge): skip the convex-hull and coverage
    /// checks, which a trimmed mesh cannot pass.
    #[arg(long)]
    pub trimmed: bool,
    /// The mesh is deliberately not Delaunay (made with --no-flat-triangles).
    #[arg(long)]
    pub not_delaunay: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let (vertices, triangles) = sweeptin::input::read_ply(&args.mesh)?;
    let segments = if args.breaklines.is_empty() {
        Vec::new()
    } else {
        let lines = read_files(&args.breaklines)?;
        lines.clean(&CleanOptions::default())?.segment_coords()
    };
    let check = CdtCheck {
        convex_hull: !args.trimmed,
        delaunay: !args.not_delaunay,
    };
    let report =
        validate_cdt_with(&vertices, &triangles, &segments, &check).with_context(|| {
            format!(
                "{} is not valid ({} vertices, {} triangles)",
                args.mesh.display(),
                vertices.len(),
                triangles.len()
            )
        })?;
    let extra = if segments.is_empty() {
        String::new()
    } else {
        format!(
            ", {} breakline segments, {} constrained edges",
            segments.len(),
            report.constrained_edges
        )
    };
    println!(
        "{}: valid ({} vertices, {} triangles{extra})",
        args.mesh.display(),
        vertices.len(),
        triangles.len()
    );
    Ok(())
}
