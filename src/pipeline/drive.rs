//! Phase 2: merge → sweep → write, in three threads joined by bounded crossbeam channels, so
//! merging, sweeping and writing overlap and memory stays bounded.

use super::emit::{Collected, Emitter};
use super::line_feed::{LineFeed, WithLines};
use super::lines::{FarHeights, LINE_FLAG, LineSummary, Prepared};
use super::read::{self, ReadResult};
use super::{
    AnonPeak, Frame, RunConfig, RunSummary, StreamInfo, SweepAxis, Timings, TriangleSink, peak_rss,
};
use crate::error::{Error, Result};
use crate::finalise::{Event, StreamConfig, StreamPoint, StreamingSweep};
use crate::sink::MeshSink;
use crate::sort::external::{Dedup, ExternalSorter, Merge, SortRecord};
use crate::sweep::ConstraintVertex;
use crossbeam_channel::{Receiver, Sender, bounded};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;
use std::time::Instant;

/// Points per batch from the merge thread to the sweep.
const POINT_BATCH: usize = 8192;
/// Events per batch from the sweep to the writer.
const EVENT_BATCH: usize = 16384;
/// Points between watermarks.
const WATERMARK_EVERY: u64 = 1 << 16;

/// The progress bar of a run: points against the headers' total while reading (points read,
/// not kept), then points swept; the rate in whole units (`1.36 M pts/s`).
pub(super) fn bar(enabled: bool) -> ProgressBar {
    if !enabled {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::new(0);
    b.set_style(
        ProgressStyle::with_template(
            "{msg:>12} [{elapsed_precise}] {wide_bar} {human_pos}/{human_len} pts \
             ({rate}, ETA {eta})",
        )
        .expect("valid template")
        .with_key(
            "rate",
            |s: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&rate(s.per_sec()));
            },
        ),
    );
    b
}

/// A rate of points per second in whole units: `950 pts/s`, `12.5 k pts/s`, `1.36 M pts/s`.
pub(crate) fn rate(per_sec: f64) -> String {
    match per_sec {
        r if !r.is_finite() || r < 1e3 => format!("{:.0} pts/s", r.max(0.0)),
        r if r < 1e6 => format!("{:.1} k pts/s", r / 1e3),
        r => format!("{:.2} M pts/s", r / 1e6),
    }
}

pub(crate) fn run(
    config: &RunConfig,
    lines: Option<&Prepared>,
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<RunSummary> {
    let start = Instant::now();
    let (input, options) = (config.input(), config.options());
    // Breaklines and the terrain products work in y order (pending segments, watermarks), and
    // so does whoever reads back a mesh format that keeps the watermarks (`.stin`).
    let free_axis =
        lines.is_none() && sinks.is_empty() && !mesh.as_ref().is_some_and(|m| m.keeps_watermarks());
    if options.sweep_axis == SweepAxis::X && !(lines.is_none() && sinks.is_empty()) {
        return Err(Error::Options(
            "--sweep-axis x works only for plain meshes (no breaklines, trimming or terrain \
             products, which need the sweep along y)"
                .into(),
        ));
    }
    // Half the budget for the sort's chunk; the rest covers the sweep's working set, the
    // channels and the writers' buffers.
    let mut sorter = ExternalSorter::new(options.mem / 2, config.tmp_dir());
    let pb = bar(options.progress);
    pb.set_message("reading");
    let rd = read::read_into(config, free_axis, &mut sorter, &mut |n, total| {
        if let Some(t) = total {
            pb.set_length(t);
        } else {
            pb.set_length(n);
        }
        pb.set_position(n);
    })?;
    let mut rd = rd;
    let mut expected = rd.points;
    // Streamed breaklines join the points in the merge thread ([`super::line_feed`]).
    let feed = lines.and_then(|l| l.feed.lock().ok()?.take());
    if let Some(f) = &feed {
        let b = f.bounds;
        rd.bounds = [
            rd.bounds[0].min(b[0]),
            rd.bounds[1].min(b[1]),
            rd.bounds[2].max(b[2]),
            rd.bounds[3].max(b[3]),
        ];
        expected += f.vertices;
    }
    let fed = feed.is_some();
    if let Some(g) = lines.and_then(|l| l.pslg.as_ref()) {
        for (c, v) in g.vertices.iter().enumerate() {
            let (x, y) = (v[0] + 0.0, v[1] + 0.0);
            sorter.push(SortRecord {
                x,
                y,
                z: v[2],
                index: LINE_FLAG | c as u64,
            })?;
            rd.bounds = [
                rd.bounds[0].min(x),
                rd.bounds[1].min(y),
                rd.bounds[2].max(x),
                rd.bounds[3].max(y),
            ];
        }
        expected += g.vertices.len() as u64;
    }
    if rd.points == 0 {
        return Err(Error::NothingLeft {
            files: input.paths.clone(),
            what: rd.stats.describe(0),
        });
    }
    let anon = AnonPeak::default();
    anon.sample();
    pb.set_message("sorting");
    let merge = sorter.finish()?;
    let sort = merge.stats();
    let read_sort = start.elapsed().as_secs_f64();

    let phase2 = Instant::now();
    let info = StreamInfo {
        crs: rd.crs.clone(),
        bounds: world_bounds(&rd),
    };
    for s in sinks.iter_mut() {
        s.begin(&info)?;
    }
    pb.set_message("triangulating");
    pb.set_length(rd.points);
    pb.set_position(0);
    // The flat-triangle pass holds every vertex anyway.
    let corners = super::emit::corners_needed(!sinks.is_empty(), lines.map(|l| &l.trim))
        && !lines.is_some_and(|l| l.flat);
    let sinks_ref: &mut [&mut dyn TriangleSink] = &mut *sinks;
    let outcome = std::thread::scope(|scope| {
        let (ptx, prx) = bounded::<PointBatch>(4);
        let (etx, erx) = bounded::<Vec<Event>>(4);
        let policy = input.duplicates;
        let z_range = rd.z_range;
        let merger = scope.spawn(move || merge_points(merge, feed, z_range, policy, ptx));
        let frame = rd.frame;
        let writer = scope.spawn(move || write_events(erx, frame, lines, mesh, sinks_ref));
        let cfg = StreamConfig {
            x_sample: rd.x_sample.clone(),
            bounds: rd.bounds,
            expected_points: expected,
            spill: Some(crate::finalise::SpillPolicy {
                dir: config.tmp_dir().to_path_buf(),
                mem: options.mem,
            }),
            corners,
        };
        let swept = sweep_points(&cfg, lines, fed, prx, etx, &pb, &anon);
        let duplicates = joined(merger.join(), "merge");
        let written = joined(writer.join(), "writer");
        (swept, duplicates, written)
    });
    let (swept, duplicates, written) = outcome;
    // A merge error ends the points early: report it before anything built from them. A writer
    // error closes its channel, which stops the sweep: report it before the sweep's.
    let (duplicates, fed_far) = duplicates?;
    let (vertices, triangles, trimmed, flat) = written?;
    let (sweep, stream, kept, cstats) = swept?;
    let triangulate_write = phase2.elapsed().as_secs_f64();
    pb.finish_and_clear();
    if triangles == 0 {
        let filtered = rd.stats.read > rd.stats.kept || rd.stats.skipped > 0;
        return Err(if trimmed > 0 {
            Error::trimmed_all(trimmed)
        } else if kept < 3 && filtered {
            Error::NothingLeft {
                files: input.paths.clone(),
                what: rd.stats.describe(kept),
            }
        } else if kept < 3 {
            Error::TooFewPoints {
                distinct: kept,
                total: rd.points,
            }
        } else {
            Error::AllCollinear { distinct: kept }
        });
    }
    anon.sample();
    let fin = Instant::now();
    let mut products = Vec::with_capacity(sinks.len());
    for s in sinks.iter_mut() {
        products.push(s.finish()?);
    }
    Ok(RunSummary {
        points_read: rd.points,
        points_kept: kept,
        duplicates,
        triangles,
        vertices,
        seconds: Timings {
            read_sort,
            triangulate_write,
            finish: fin.elapsed().as_secs_f64(),
        },
        peak_rss_bytes: peak_rss(),
        peak_anon_bytes: anon.get(),
        sort,
        sweep,
        stream,
        products,
        crs: rd.crs.as_ref().and_then(|c| c.definition()),
        sweep_axis: if rd.frame.swap {
            SweepAxis::X
        } else {
            SweepAxis::Y
        },
        breaklines: lines.map(|l| LineSummary {
            constraints: cstats,
            trimmed_triangles: trimmed,
            flat,
            far_heights: if fed {
                fed_far
            } else {
                FarHeights::of(l, rd.z_range)
            },
            ..l.summary.clone()
        }),
        tiles: None,
        warnings: {
            let mut w = rd.warnings.clone();
            w.extend(front_warning(&stream, options.mem, config.tmp_dir()));
            w
        },
        ground: None,
    })
}

/// Bytes a triangle held by the sweep costs with its share of vertices and queue entries
/// (measured: 1 M points on a line, every triangle live to the end, 146 MB of tables above the
/// base, sampled; the end's events now go in batches).
pub(crate) const LIVE_TRIANGLE_BYTES: u64 = 150;

/// The warning for a sweep that held more triangles than a quarter of `--mem` pays for: points
/// on (or near) one line or one circle keep every triangle open to the end of the sweep, and no
/// order of insertion can finish them early. Their tables then go to temporary files
/// (`crate::finalise::SpillPolicy`), which the warning names with their size; when they could
/// not (no room, an address-space limit), memory grew past `--mem` (docs/RELIABILITY.md, known
/// limits).
fn front_warning(stream: &crate::finalise::StreamStats, mem: u64, tmp: &Path) -> Option<String> {
    let held = stream
        .peak_live_triangles
        .saturating_mul(LIVE_TRIANGLE_BYTES);
    // A large share of all the triangles, not a small budget against an ordinary front.
    let open = stream.peak_live_triangles.saturating_mul(10) > stream.triangles;
    let lead = format!(
        "the sweep held {} triangles at once: the points lie nearly on one line or one circle, \
         where every triangle stays open to the end of the sweep",
        stream.peak_live_triangles
    );
    if stream.peak_spilled_bytes > 0 && open {
        return Some(format!(
            "{lead}; their tables ({}) were kept in a temporary file under {} rather than in \
             --mem {} (slower; see docs/RELIABILITY.md)",
            crate::human_bytes(stream.peak_spilled_bytes),
            tmp.display(),
            crate::human_bytes(mem)
        ));
    }
    (held > mem / 2 && open).then(|| {
        format!(
            "{lead}, and they (about {}) could not go to a temporary file: memory grew past \
             --mem {} (a known limit, see docs/RELIABILITY.md); give more --mem or room under \
             --tmp-dir, or add points that close the surface",
            crate::human_bytes(held),
            crate::human_bytes(mem)
        )
    })
}

/// The result of a worker thread; a panic in it becomes [`Error::Internal`] with its message.
fn joined<T>(result: std::thread::Result<Result<T>>, thread: &str) -> Result<T> {
    result.unwrap_or_else(|payload| Err(Error::panicked(thread, &*payload)))
}

fn world_bounds(rd: &ReadResult) -> [f64; 4] {
    let lo = rd.frame.world([rd.bounds[0], rd.bounds[1]], 0.0);
    let hi = rd.frame.world([rd.bounds[2], rd.bounds[3]], 0.0);
    [lo[0], lo[1], hi[0], hi[1]]
}

/// A batch of points from the merge thread, with the records of the streamed breakline
/// vertices among them, in order.
type PointBatch = (Vec<StreamPoint>, Vec<ConstraintVertex>);

/// Merge thread: sorted, de-duplicated points in batches, with the streamed breakline vertices
/// (`feed`) merged in. Returns the number of duplicates and the far-heights warning of the
/// streamed vertices (the points' heights `z_range`), or the error that cut the merge short (an
/// unreadable spill file).
fn merge_points(
    mut merge: Merge,
    feed: Option<LineFeed>,
    z_range: [f64; 2],
    policy: crate::sort::memory::DuplicatePolicy,
    out: Sender<PointBatch>,
) -> Result<(u64, Option<FarHeights>)> {
    let mut src = WithLines::new(&mut merge, feed, z_range);
    let records = src.records();
    let mut d = Dedup::new(&mut src, policy).with_mark(LINE_FLAG);
    let mut batch = Vec::with_capacity(POINT_BATCH);
    let mut recs = Vec::new();
    for r in d.by_ref() {
        let constraint = if r.index & LINE_FLAG != 0 {
            if let Some(rec) = records.borrow_mut().pop_front() {
                recs.push(rec);
            }
            (r.index & !LINE_FLAG) as u32
        } else {
            crate::sweep::NO_CONSTRAINT
        };
        batch.push(StreamPoint {
            xy: [r.x, r.y],
            z: r.z,
            index: r.index,
            constraint,
        });
        if batch.len() == POINT_BATCH {
            let b = (std::mem::take(&mut batch), std::mem::take(&mut recs));
            if out.send(b).is_err() {
                return Ok((d.duplicates, None));
            }
            batch.reserve(POINT_BATCH);
        }
    }
    let duplicates = d.duplicates;
    // An error must not reach the sweep as a normal end of input.
    let far = src.finish()?;
    if !batch.is_empty() {
        let _ = out.send((batch, recs));
    }
    Ok((duplicates, far))
}

type Swept = (
    crate::sweep::SweepStats,
    crate::finalise::StreamStats,
    u64,
    crate::sweep::ConstraintStats,
);

/// Sweep thread (the caller's): points in, events out.
fn sweep_points(
    cfg: &StreamConfig,
    lines: Option<&Prepared>,
    fed: bool,
    points: Receiver<PointBatch>,
    events: Sender<Vec<Event>>,
    pb: &ProgressBar,
    anon: &AnonPeak,
) -> Result<Swept> {
    let mut sweep: Option<StreamingSweep> = None;
    let mut kept = 0u64;
    let mut next_watermark = 0u64;
    let mut out = Vec::with_capacity(EVENT_BATCH);
    let send = |out: &mut Vec<Event>| -> bool {
        events
            .send(std::mem::replace(out, Vec::with_capacity(EVENT_BATCH)))
            .is_ok()
    };
    for (batch, recs) in points.iter() {
        let mut recs = recs.into_iter();
        for p in batch {
            kept += 1;
            // A streamed breakline vertex comes with its record.
            let rec = if fed && p.constraint != crate::sweep::NO_CONSTRAINT {
                Some(recs.next().ok_or_else(|| {
                    Error::Internal(format!(
                        "breakline vertex {} came without its record from the merge",
                        p.constraint
                    ))
                })?)
            } else {
                None
            };
            match sweep.as_mut() {
                None => {
                    let first = p.constraint;
                    let mut s = StreamingSweep::new(p, cfg);
                    if let Some(g) = lines.and_then(Prepared::graph) {
                        s.set_constraints(g, first)?;
                    } else if fed {
                        s.set_fed_constraints(rec.map(|r| (first, r)))?;
                    }
                    sweep = Some(s);
                }
                Some(s) => s.push_fed(p, rec)?,
            }
            if kept.is_multiple_of(WATERMARK_EVERY) {
                let s = sweep.as_mut().expect("started");
                // A watermark visits every live triangle: with more of them than points between
                // two watermarks (a line's fan holds them all) it is emitted once per that many
                // points, so its cost stays linear.
                if kept >= next_watermark {
                    s.emit_watermark();
                    next_watermark = kept + s.live_triangles().max(WATERMARK_EVERY);
                }
                pb.set_position(kept);
                anon.sample();
            }
        }
        let s = sweep.as_mut().expect("a batch is never empty");
        if s.pending_events() >= EVENT_BATCH {
            s.take_events(&mut out);
            if !send(&mut out) {
                // The writer stopped (its error is reported by the caller).
                return Err(Error::Interrupted);
            }
        }
    }
    let Some(mut s) = sweep else {
        return Ok(Default::default());
    };
    // Points on a line hold every triangle to the end: hand them over in batches, never all
    // at once (3 events a triangle, 40 bytes each).
    if !s.finish_in_batches(EVENT_BATCH, |ev| {
        out.append(ev);
        send(&mut out)
    }) {
        return Err(Error::Interrupted);
    }
    s.take_events(&mut out);
    if !send(&mut out) {
        return Err(Error::Interrupted);
    }
    pb.set_position(kept);
    Ok((s.stats(), s.stream_stats(), kept, s.constraint_stats()))
}

/// Writer thread: events to the mesh sink and the triangle sinks, in real-world coordinates.
/// Returns the numbers of vertices and triangles written, of triangles trimmed, and what the flat
/// triangle pass did.
fn write_events(
    events: Receiver<Vec<Event>>,
    frame: Frame,
    lines: Option<&Prepared>,
    mesh: Option<&mut (dyn MeshSink + Send)>,
    sinks: &mut [&mut dyn TriangleSink],
) -> Result<Written> {
    // Fault injection for the test of the exit status after a panic in a worker thread.
    if std::env::var_os("SWEEPTIN_TEST_PANIC").is_some_and(|v| v == "writer") {
        panic!("injected panic (SWEEPTIN_TEST_PANIC=writer)");
    }
    let mut emit = Emitter::new(frame, mesh, sinks, lines.map(|l| &l.trim));
    let flat_graph = lines.filter(|l| l.flat).map(|l| {
        l.pslg
            .as_ref()
            .map_or((&[][..], &[][..]), |g| (&g.segments[..], &g.lines[..]))
    });
    let mut flat = None;
    if let Some((segments, line_ids)) = flat_graph {
        let mut all = Collected::default();
        for batch in events.iter() {
            for ev in batch {
                all.event(ev);
            }
        }
        flat = Some(all.finish(segments, line_ids, &mut emit)?);
    } else {
        for batch in events.iter() {
            for ev in batch {
                emit.event(ev)?;
            }
        }
    }
    let (v, t, trimmed) = emit.counts();
    Ok((v, t, trimmed, flat))
}

type Written = (u64, u64, u64, Option<crate::breaklines::flat::FlatStats>);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_in_whole_units() {
        assert_eq!(rate(1_356_317.194_9), "1.36 M pts/s");
        assert_eq!(rate(12_480.0), "12.5 k pts/s");
        assert_eq!(rate(950.4), "950 pts/s");
        assert_eq!(rate(f64::NAN), "0 pts/s");
    }

    #[test]
    fn a_worker_panic_is_an_internal_error() {
        let text = std::thread::spawn(|| -> Result<()> { panic!("boom") }).join();
        let formatted = std::thread::spawn(|| -> Result<()> { panic!("boom {}", 2) }).join();
        for (r, want) in [(text, "boom"), (formatted, "boom 2")] {
            match joined(r, "merge") {
                Err(Error::Internal(m)) => {
                    assert_eq!(m, format!("the merge thread panicked: {want}"))
                }
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(joined(Ok(Ok(7)), "writer").unwrap(), 7);
    }
}
