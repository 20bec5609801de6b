//! Joining a TIN plan: every task's mesh pieces ([`crate::output::pieces`]) into one mesh.
//!
//! Tasks are taken in plan order (rows of tiles south to north, west to east in a row), each
//! task's pieces in the order it wrote them, through the same writer as one tiled run
//! (`tiles::emit::TileWriter`): a vertex is numbered when a triangle first uses it and
//! forgotten when the piece of the tile that owns it has said how many triangles use it and
//! that many were written, so only the vertices along task edges wait. The mesh is the triangle
//! set of one run (each triangle once, from the task owning its lowest vertex); its order is the
//! plan's order, so the same plan always gives the same bytes.

use super::{Plan, TaskRecord};
use crate::error::{Error, Result};
use crate::output::pieces::PieceReader;
use crate::output::{MeshMeta, create_mesh_sink};
use crate::sink::MeshSummary;
use crate::tiles::emit::TileWriter;
use crate::tiles::worker::TileOutput;
use std::path::{Path, PathBuf};

/// What merging a TIN plan wrote.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct TinMergeSummary {
    /// The mesh written.
    pub path: PathBuf,
    /// Vertices and triangles written, and the file's size.
    pub vertices: u64,
    /// See `vertices`.
    pub triangles: u64,
    /// See `vertices`.
    pub bytes: u64,
    /// Triangles trimming dropped (`--max-edge`, outside the boundary, inside holes).
    pub trimmed: u64,
    /// Most vertices waiting for their last triangle at once (those along task edges).
    pub peak_waiting_vertices: u64,
}

/// Joins the pieces of `records` (every task of `plan` in `dir`, in order) into the mesh `out`, whose
/// format its extension names (`.ply`, `.obj`, `.xml`, `.stin`).
///
/// # Errors
/// [`Error::Options`] for an unknown mesh extension; [`Error::Format`] for a damaged pieces
/// file; [`Error::Internal`] when vertices are left waiting (pieces of another plan); the
/// writer's errors.
pub(super) fn merge_tin(
    plan: &Plan,
    dir: &super::PlanDir,
    records: &[TaskRecord],
    out: &Path,
    crs: Option<String>,
) -> Result<TinMergeSummary> {
    let meta = MeshMeta {
        crs,
        comments: vec![format!(
            "sweeptin {} Delaunay TIN, merged from {} tasks of a plan",
            env!("CARGO_PKG_VERSION"),
            records.len()
        )],
    };
    let mut sink = create_mesh_sink(out, None, &meta)?;
    // Breaklines make the mesh constrained (trimming rings too, which the writer declares): its
    // PLY or `.stin` says so, and `check` tests it as the constrained mesh it is.
    if plan
        .job
        .lines
        .as_ref()
        .is_some_and(|l| !l.breaklines.is_empty())
    {
        sink.declare(crate::validate::MeshKind {
            constrained: true,
            ..crate::validate::MeshKind::default()
        })?;
    }
    // The pieces hold every triangle: the merge trims (boundary, holes, --max-edge).
    let trim = match (&plan.job.lines, plan.job.max_edge) {
        (Some(l), m) => Some(l.trim(m)?).filter(|t| !t.keeps_all()),
        (None, Some(l)) => Some(crate::breaklines::Trim::new(None, &[], Some(l))?),
        (None, None) => None,
    };
    let mut no_sinks: [&mut dyn crate::sink::TriangleSink; 0] = [];
    let mut writer = TileWriter::new(Some(&mut *sink), &mut no_sinks, trim);
    let mut row = None;
    for (t, r) in plan.tiles.iter().zip(records) {
        if r.status == "empty" && r.outputs.is_empty() {
            // An empty task wrote no pieces: it has no triangle and no vertex.
            continue;
        }
        let path = r
            .outputs
            .iter()
            .find(|(n, _)| n == "tin")
            .map(|(_, p)| p.clone())
            .ok_or_else(|| Error::Options(format!("task {} recorded no mesh pieces", r.index)))?;
        if row != Some(t.ty) {
            // Later tasks' triangles have their lowest vertex in this row of tiles or above.
            writer.watermark(t.bounds[1])?;
            row = Some(t.ty);
        }
        // A damaged file says which task to run again.
        let again = |e: Error| match e {
            Error::Format { message, .. } => Error::Format {
                path: path.clone(),
                message: format!("{message}; {}", super::task::run_again(dir, r.index, false)),
            },
            e => e,
        };
        // Pieces on S3 are read from a copy in the temporary directory.
        let copy = dir.local(&path)?;
        let mut pieces = PieceReader::open(&copy.path).map_err(again)?;
        while let Some(p) = pieces.next_piece().map_err(again)? {
            writer.tile(&TileOutput {
                tile: p.tile,
                vertices: p.vertices,
                triangles: p.triangles,
                degree: p.degree,
                ..TileOutput::default()
            })?;
        }
    }
    let inside = |x: f64, y: f64| {
        plan.tiles.iter().any(|t| {
            let b = &t.bounds;
            x >= b[0] && x < b[2] && y >= b[1] && y < b[3]
        })
    };
    writer.release(|x, y| !inside(x, y))?;
    if writer.pending() != 0 {
        return Err(Error::Internal(format!(
            "{} vertices were left waiting for triangles after the last task: are the tasks' \
             pieces all of this plan?",
            writer.pending()
        )));
    }
    let (trimmed, peak) = (writer.trimmed, writer.peak_live as u64);
    drop(writer);
    let MeshSummary {
        vertices,
        triangles,
        bytes,
    } = sink.finish()?;
    Ok(TinMergeSummary {
        path: out.to_path_buf(),
        vertices,
        triangles,
        bytes,
        trimmed,
        peak_waiting_vertices: peak,
    })
}
