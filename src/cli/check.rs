//! `sweeptin check`: validate a mesh file.

use anyhow::Context;
use std::path::PathBuf;
use sweeptin::breaklines::{CleanOptions, read_files};
use sweeptin::input::{StinEvent, StinReader};
use sweeptin::validate::MeshKind;
use sweeptin::validate::{CdtCheck, StreamCheck, StreamChecker, StreamReport, validate_cdt_with};

/// Arguments of `sweeptin check`.
#[derive(clap::Args, Debug)]
#[command(after_help = "\
Memory: a .ply is checked in memory: its vertices and triangles (about 36 bytes a vertex and 12 a
triangle) and the check's own tables (about 40 bytes a triangle): some 1.3 GB for 18 million
triangles. A .stin (sweeptin tin -o mesh.stin) is checked as it streams, holding only the live
vertices and the edges waiting for their twin, as the sweep that wrote it did: megabytes for any
size. The streaming check tests every triangle's orientation, every edge's twin and Delaunay
property, unused vertices and the convex hull corner by corner; it takes no --breaklines.

What is checked: a mesh sweeptin wrote says what it is (a PLY `comment sweeptin: …` line, the
.stin header's flags; docs/FORMATS.md): `trimmed` (its boundary is not the convex hull: no hull
and coverage checks), `not-delaunay` (tiles or windows joined, --no-flat-triangles: no Delaunay
test), `constrained` (breaklines, boundary rings: the Delaunay test only with the lines given as
--breaklines, since the file does not list its constrained edges). So `sweeptin check OUT` passes
on every mesh the tool writes, and fails on damage: a flipped edge, a moved vertex, a missing or
overlapping triangle. --trimmed and --not-delaunay add to what the file says; a mesh from
elsewhere (no such line) is checked as a Delaunay triangulation of its convex hull.")]
pub struct Args {
    /// The mesh to validate: .ply (ASCII or binary, triangles only; held in memory) or .stin
    /// (streaming mesh; checked in bounded memory).
    pub mesh: PathBuf,
    /// The breaklines the mesh was made with (repeatable; also the --boundary and --holes files):
    /// every segment must be made of mesh edges, and only edges off the segments must be Delaunay.
    #[arg(long = "breaklines", value_name = "FILE")]
    pub breaklines: Vec<PathBuf>,
    /// The mesh was trimmed (--boundary, --holes, --max-edge): skip the convex-hull and coverage
    /// checks, which a trimmed mesh cannot pass (a mesh sweeptin wrote says so itself).
    #[arg(long)]
    pub trimmed: bool,
    /// The mesh is deliberately not Delaunay (made with --no-flat-triangles; a mesh sweeptin
    /// wrote says so itself).
    #[arg(long)]
    pub not_delaunay: bool,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let is_stream = args
        .mesh
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("stin"));
    if is_stream {
        return check_stream(&args);
    }
    let kind = sweeptin::input::read_ply_kind(&args.mesh)?.union(flags(&args));
    let (vertices, triangles) = sweeptin::input::read_ply(&args.mesh)?;
    let segments = if args.breaklines.is_empty() {
        Vec::new()
    } else {
        let lines = read_files(&args.breaklines)?;
        lines.clean(&CleanOptions::default())?.segment_coords()
    };
    let check = CdtCheck::for_kind(kind, !segments.is_empty());
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
        "{}: valid ({} vertices, {} triangles{extra}{})",
        args.mesh.display(),
        vertices.len(),
        triangles.len(),
        skipped(kind, check.convex_hull, check.delaunay)
    );
    Ok(())
}

/// The kind the flags add.
fn flags(args: &Args) -> MeshKind {
    MeshKind {
        trimmed: args.trimmed,
        not_delaunay: args.not_delaunay,
        ..MeshKind::default()
    }
}

/// What was not checked, and why: `; a constrained trimmed mesh: no convex-hull check, no
/// Delaunay test`, or nothing when everything was.
fn skipped(kind: MeshKind, hull: bool, delaunay: bool) -> String {
    let mut off = Vec::new();
    if !hull {
        off.push("no convex-hull check");
    }
    if !delaunay {
        off.push(if kind.constrained && !kind.not_delaunay {
            "no Delaunay test without its --breaklines"
        } else {
            "no Delaunay test"
        });
    }
    if off.is_empty() {
        String::new()
    } else {
        format!("; a {} mesh: {}", kind.words(), off.join(", "))
    }
}

/// `check mesh.stin`: the streaming check, in bounded memory.
fn check_stream(args: &Args) -> anyhow::Result<()> {
    if !args.breaklines.is_empty() {
        return Err(sweeptin::Error::Options(
            "the streaming check of a .stin does not take --breaklines: write the mesh as .ply \
             to check it against its breaklines"
                .into(),
        )
        .into());
    }
    let mut reader = StinReader::open(&args.mesh)?;
    let kind = reader.kind().union(flags(args));
    let check = StreamCheck::for_kind(kind);
    let r = validate_stream(&mut reader, check)
        .with_context(|| format!("{} is not valid", args.mesh.display()))?;
    println!(
        "{}: valid ({} vertices, {} triangles; checked holding at most {} vertices and {} \
         edges{})",
        args.mesh.display(),
        r.report.vertices,
        r.report.triangles,
        r.peak_live_vertices,
        r.peak_pending_edges,
        skipped(kind, check.convex_hull, check.delaunay)
    );
    Ok(())
}

/// Feeds the events of the streaming mesh `r` to a [`StreamChecker`].
fn validate_stream(r: &mut StinReader, check: StreamCheck) -> sweeptin::Result<StreamReport> {
    let mut c = StreamChecker::new(check);
    while let Some(ev) = r.next()? {
        match ev {
            StinEvent::Vertex(p) => c.vertex(p)?,
            StinEvent::Triangle { ids, points } => c.triangle(ids, points)?,
            StinEvent::VertexDone(v) => c.done(v)?,
            StinEvent::Watermark(_) => {}
        }
    }
    c.finish()
}
