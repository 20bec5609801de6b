//! The tiled run: [`crate::tiles`] on every core, summarised like the sweep's.

use super::config::{RunConfig, Source};
use super::drive::bar;
use super::{AnonPeak, RunSummary, SweepAxis, Timings, peak_rss};
use crate::error::Result;
use crate::sink::{MeshSink, TriangleSink};
use crate::tiles::TileOptions;
use std::time::Instant;

/// Can `input` run in tiles? LAS/LAZ points, with breaklines, trimming polygons and
/// `--max-edge` (see [`crate::tiles::worker`] for why constrained tiles are exact); not the
/// flat-triangle pass (its flips need neighbours across the whole triangulation). A plan's task
/// takes lines too, every vertex with its z (it prepares the whole graph itself, as every other
/// task does, but cannot drape or clip: that needs all the points).
pub(crate) fn applies(config: &RunConfig) -> bool {
    let l = &config.input().lines;
    config.source() == Source::Lidar
        && !l.no_flat_triangles
        && config.options().sweep_axis != SweepAxis::X
}

pub(crate) fn run(
    config: &RunConfig,
    tiles: &TileOptions,
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<RunSummary> {
    let start = Instant::now();
    let options = config.options();
    let anon = AnonPeak::default();
    let pb = bar(options.progress);
    let mut phase = String::new();
    let mut progress = |what: &str, n: u64, total: u64| {
        if phase != what {
            phase = what.to_string();
            pb.set_message(phase.clone());
            anon.sample();
        }
        pb.set_length(total);
        pb.set_position(n);
    };
    let input = config.input();
    let l = &input.lines;
    // Breaklines and rings: read, cleaned and draped (lines without z: a points-only tiled run
    // first), as for the sweep. A plan's task sees only the files near its tile: its lines must
    // have every z (the plan checked), and it never drapes or clips.
    let prepared = if l.breaklines.is_empty() && l.boundary.is_none() && l.holes.is_none() {
        None
    } else if tiles.scope.is_some() {
        Some(super::lines::prepare(l, config.read_lines(), None)?)
    } else {
        let points_only = config.points_only();
        Some(super::lines::prepare(
            l,
            config.read_lines(),
            Some(&mut |sink| run(&points_only, tiles, None, &mut [sink]).map(|_| ())),
        )?)
    };
    let job = crate::tiles::TileJob {
        paths: &input.paths,
        filter: &input.filter,
        duplicates: input.duplicates,
        max_edge: input.lines.max_edge,
        lines: prepared.as_ref().and_then(|p| p.pslg.as_ref()),
        trim: prepared.as_ref().map(|p| &p.trim),
        mem: options.mem,
        tmp: config.tmp_dir(),
        crs: config.declared_crs(),
    };
    let line_vertices = job.lines.map_or(0, |g| g.vertices.len() as u64);
    let r = crate::tiles::run(&job, tiles, &mut progress, mesh, sinks)?;
    pb.finish_and_clear();
    anon.sample();
    let triangulate_write = start.elapsed().as_secs_f64() - r.read_sort;
    let fin = Instant::now();
    let mut products = Vec::with_capacity(sinks.len());
    for s in sinks.iter_mut() {
        products.push(s.finish()?);
    }
    Ok(RunSummary {
        points_read: r.points_read,
        points_kept: r.points_kept,
        // Kept vertices include the breaklines' (a line vertex at a point is one vertex).
        duplicates: (r.points_read + line_vertices).saturating_sub(r.points_kept),
        triangles: r.triangles,
        vertices: r.vertices,
        seconds: Timings {
            read_sort: r.read_sort,
            triangulate_write,
            finish: fin.elapsed().as_secs_f64(),
        },
        peak_rss_bytes: peak_rss(),
        peak_anon_bytes: anon.get(),
        sort: r.sort,
        products,
        crs: r.crs.as_ref().and_then(|c| c.definition()),
        sweep_axis: SweepAxis::Y,
        tiles: Some(r.tiles),
        warnings: r.warnings,
        breaklines: match prepared {
            Some(p) => Some(super::LineSummary {
                trimmed_triangles: r.trimmed,
                ..p.summary
            }),
            None => config.input().lines.max_edge.map(|_| super::LineSummary {
                trimmed_triangles: r.trimmed,
                ..super::LineSummary::default()
            }),
        },
        ..RunSummary::default()
    })
}
