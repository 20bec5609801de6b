//! Contour lines across tasks: every task writes the contours of the triangles it owns, so a line
//! that passes from triangles of one task to those of another ends in one task's file and goes on
//! in the other's, from the same triangle edge. The tasks write the edges their open lines start
//! and end on (`start_edge`, `end_edge`), and joining each line to the one starting on the edge it
//! ends on gives the polylines of one run over all the points (that run joins its segments by
//! the same edges). Coordinates are rounded to the job's decimals, repeated points dropped and
//! degenerate lines and those shorter than the job's minimum length left out after joining, as
//! one run does.

use super::Plan;
use crate::crs::Crs;
use crate::error::{Error, Result};
use crate::output::lines::{LineWriter, length};
use std::collections::HashMap;
use std::io::Write;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

type Pt = [f64; 2];
type Key = (u64, [u64; 4]);

/// The key of an end of a line: the edge it lies on, or (from a file without edges) its point.
fn key(level: f64, edge: Option<&[f64]>, p: Option<&Pt>) -> Option<Key> {
    if let Some(e) = edge.filter(|e| e.len() == 4) {
        return Some((level.to_bits(), [0, 1, 2, 3].map(|i| e[i].to_bits())));
    }
    p.map(|p| (level.to_bits(), [p[0].to_bits(), p[1].to_bits(), 0, 0]))
}

/// The memory an open line holds while the lines are joined: its [`Open`] record, its entry in
/// the map of starts, its successor and two flags.
const HELD_PER_LINE: u64 = (std::mem::size_of::<Open>()
    + 2 * std::mem::size_of::<(Key, usize)>()
    + std::mem::size_of::<Option<usize>>()
    + 2) as u64;

/// An open contour line of one task: its ends in memory, its points in the spill file.
struct Open {
    level: f64,
    /// First point's index in the spill file, and the count.
    offset: u64,
    len: u32,
    start: Option<Key>,
    end: Option<Key>,
}

/// One feature of a task's contour file, as the tasks write it.
#[derive(serde::Deserialize)]
struct Feature {
    properties: Properties,
    geometry: Geometry,
}

#[derive(serde::Deserialize)]
struct Properties {
    elevation: Option<f64>,
    #[serde(default)]
    closed: Option<bool>,
    #[serde(default)]
    start_edge: Option<Vec<f64>>,
    #[serde(default)]
    end_edge: Option<Vec<f64>>,
}

#[derive(serde::Deserialize)]
struct Geometry {
    coordinates: Vec<Vec<f64>>,
}

/// Calls `each` on every feature of the GeoJSON FeatureCollection in `path`, one at a time
/// (a task's file is never held whole: it can be larger than `--mem`).
fn for_each_feature(path: &Path, each: &mut dyn FnMut(Feature) -> Result<()>) -> Result<()> {
    use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
    use std::fmt;
    struct Collection<'a> {
        each: &'a mut dyn FnMut(Feature) -> Result<()>,
        failed: &'a mut Option<Error>,
        features: bool,
    }
    struct Features<'a, 'b>(&'b mut Collection<'a>);
    impl<'de> Visitor<'de> for &mut Collection<'_> {
        type Value = ();
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a GeoJSON FeatureCollection")
        }
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<(), A::Error> {
            while let Some(k) = map.next_key::<String>()? {
                if k == "features" {
                    map.next_value_seed(Features(self))?;
                } else {
                    map.next_value::<IgnoredAny>()?;
                }
            }
            Ok(())
        }
    }
    impl<'de> DeserializeSeed<'de> for Features<'_, '_> {
        type Value = ();
        fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<(), D::Error> {
            d.deserialize_seq(self)
        }
    }
    impl<'de> Visitor<'de> for Features<'_, '_> {
        type Value = ();
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an array of features")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<(), A::Error> {
            self.0.features = true;
            while let Some(f) = seq.next_element::<Feature>()? {
                if let Err(e) = (self.0.each)(f) {
                    *self.0.failed = Some(e);
                    return Err(serde::de::Error::custom("stopped"));
                }
            }
            Ok(())
        }
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut de = serde_json::Deserializer::from_reader(std::io::BufReader::new(file));
    let mut failed = None;
    let mut c = Collection {
        each,
        failed: &mut failed,
        features: false,
    };
    let parsed = de.deserialize_map(&mut c).and_then(|()| de.end());
    let features = c.features;
    if let Some(e) = failed {
        return Err(e);
    }
    parsed.map_err(|e| bad(path, format!("not a contour file: {e}")))?;
    if !features {
        return Err(bad(path, "no features"));
    }
    Ok(())
}

/// What stitching wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct StitchSummary {
    /// Features written.
    pub features: u64,
    /// Closed rings among them.
    pub rings: u64,
    /// Pieces of lines joined across tile edges.
    pub joins: u64,
    /// Lines left out as shorter than the minimum length.
    pub short_dropped: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// How the stitched lines are written: decimals of their coordinates (`None`: every bit) and
/// the shortest line kept.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StitchOptions {
    /// Decimals of the written coordinates.
    pub decimals: Option<u32>,
    /// Lines (rings included) shorter than this are left out.
    pub min_length: f64,
}

fn bad(path: &Path, m: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: m.into(),
    }
}

/// Stitches the contour files `parts` (in task order) into `out` (GeoJSON or GeoPackage, by
/// its extension). Features are read one at a time; the open lines' points wait in a temporary
/// file under `tmp` (the system's when `None`), their ends in memory (about 230 bytes a line
/// while they are joined, as one run keeps its open lines' ends), at most `mem` bytes of them.
///
/// # Errors
/// Reading or writing; [`Error::Format`] for a file that is not a contour output;
/// [`Error::Options`] for an output of another format; [`Error::OutOfMemory`] when the open
/// lines' ends would need more than `mem` (before the output appears).
pub fn stitch(
    parts: &[&Path],
    out: &Path,
    crs: Option<&Crs>,
    options: StitchOptions,
    tmp: Option<&Path>,
    mem: u64,
) -> Result<StitchSummary> {
    let mut w = LineWriter::create(out, "contours", crs, options.decimals)?;
    let mut s = StitchSummary::default();
    let mut open: Vec<Open> = Vec::new();
    let tmp_dir = tmp.map_or_else(std::env::temp_dir, Path::to_path_buf);
    let spill_file = tempfile::tempfile_in(&tmp_dir).map_err(|e| Error::io(&tmp_dir, e))?;
    let mut spill = std::io::BufWriter::with_capacity(1 << 20, spill_file);
    let mut spilled = 0u64;
    for path in parts {
        for_each_feature(path, &mut |f| {
            let level = f
                .properties
                .elevation
                .ok_or_else(|| bad(path, "a feature without elevation"))?;
            let pts = f.geometry.coordinates.iter().map(|p| {
                [
                    p.first().copied().unwrap_or(f64::NAN),
                    p.get(1).copied().unwrap_or(f64::NAN),
                ]
            });
            if f.properties.closed.unwrap_or(false) {
                let mut ring: Vec<Pt> = Vec::with_capacity(f.geometry.coordinates.len());
                for q in pts.map(|q| w.round(q)) {
                    if ring.last() != Some(&q) {
                        ring.push(q);
                    }
                }
                if ring.len() < 4 {
                    return Ok(());
                }
                if length(&ring) < options.min_length {
                    s.short_dropped += 1;
                    return Ok(());
                }
                w.line_string(
                    &serde_json::json!({"elevation": level, "closed": true}),
                    &ring,
                )?;
                s.features += 1;
                s.rings += 1;
                return Ok(());
            }
            let pts: Vec<Pt> = pts.collect();
            let start = key(level, f.properties.start_edge.as_deref(), pts.first());
            let end = key(level, f.properties.end_edge.as_deref(), pts.last());
            let len = u32::try_from(pts.len())
                .map_err(|_| bad(path, "a contour line of more than 2^32 points"))?;
            let held = (open.len() as u64 + 1).saturating_mul(HELD_PER_LINE);
            if held > mem {
                return Err(Error::OutOfMemory {
                    what: format!(
                        "the ends of {} contour lines open at the tasks' edges (at {})",
                        crate::fmt::count(open.len() as u64 + 1),
                        path.display()
                    ),
                    bytes: held,
                    hint: format!(
                        "they may take half of the merge's --mem, {} here: give merge a larger \
                         --mem",
                        crate::human_bytes(mem)
                    ),
                });
            }
            spill
                .write_all(bytemuck::cast_slice(&pts))
                .map_err(|e| Error::io(&tmp_dir, e))?;
            open.push(Open {
                level,
                offset: spilled,
                len,
                start,
                end,
            });
            spilled += u64::from(len);
            Ok(())
        })?;
    }
    let spill = spill
        .into_inner()
        .map_err(|e| Error::io(&tmp_dir, e.into_error()))?;
    // Join ends to starts.
    let mut by_start: HashMap<Key, usize> = HashMap::with_capacity(open.len());
    for (i, l) in open.iter().enumerate() {
        if let Some(k) = l.start {
            by_start.insert(k, i);
        }
    }
    let next: Vec<Option<usize>> = open
        .iter()
        .map(|l| l.end.and_then(|k| by_start.get(&k).copied()))
        .collect();
    drop(by_start);
    let mut has_prev = vec![false; open.len()];
    for j in next.iter().flatten() {
        has_prev[*j] = true;
    }
    let mut used = vec![false; open.len()];
    let mut piece: Vec<Pt> = Vec::new();
    let mut emit = |start: usize, used: &mut Vec<bool>, w: &mut LineWriter| -> Result<()> {
        let level = open[start].level;
        let mut pts: Vec<Pt> = Vec::new();
        let mut i = start;
        let mut closed = false;
        loop {
            used[i] = true;
            if !pts.is_empty() {
                s.joins += 1;
            }
            piece.resize(open[i].len as usize, [0.0; 2]);
            spill
                .read_exact_at(
                    bytemuck::cast_slice_mut(&mut piece),
                    open[i].offset * std::mem::size_of::<Pt>() as u64,
                )
                .map_err(|e| Error::io(&tmp_dir, e))?;
            for q in piece.iter().map(|&q| w.round(q)) {
                if pts.last() != Some(&q) {
                    pts.push(q);
                }
            }
            match next[i] {
                Some(j) if j == start => {
                    closed = true;
                    break;
                }
                Some(j) if !used[j] => i = j,
                _ => break,
            }
        }
        // As one run: a ring of fewer than 4 points, or a line of fewer than 2, is left out.
        if pts.len() < if closed { 4 } else { 2 } {
            return Ok(());
        }
        if length(&pts) < options.min_length {
            s.short_dropped += 1;
            return Ok(());
        }
        s.features += 1;
        if closed {
            s.rings += 1;
        }
        w.line_string(
            &serde_json::json!({"elevation": level, "closed": closed}),
            &pts,
        )
    };
    for i in 0..open.len() {
        if !has_prev[i] && !used[i] {
            emit(i, &mut used, &mut w)?;
        }
    }
    // What is left are cycles: rings cut by tile edges.
    for i in 0..open.len() {
        if !used[i] {
            emit(i, &mut used, &mut w)?;
        }
    }
    s.bytes = w.finish()?;
    Ok(s)
}

/// Stitches the tasks' contours into `out`, the ends of the lines open at the tasks' edges
/// within half of `mem` (the merge's budget).
///
/// # Errors
/// As [`stitch`]; unfinished tasks.
pub fn merge_contours(
    plan: &Plan,
    dir: &super::PlanDir,
    out: &Path,
    crs: Option<&Crs>,
    mem: u64,
) -> Result<StitchSummary> {
    let recs = super::merge::records(plan, dir)?;
    // Copies of parts on S3 (the stitcher reads files), in the temporary directory.
    let copies = super::merge::outputs(&recs, "contours")?
        .into_iter()
        .map(|(_, p)| dir.local(p))
        .collect::<Result<Vec<_>>>()?;
    let parts: Vec<&Path> = copies.iter().map(|c| c.path.as_path()).collect();
    let levels = match &plan.job.product {
        super::Product::Dem {
            contours: Some(l), ..
        }
        | super::Product::Contours(l) => *l,
        _ => {
            return Err(Error::Internal(
                "contours merged from a plan without".into(),
            ));
        }
    };
    let decimals = levels.decimals.unwrap_or_else(|| {
        let paths: Vec<PathBuf> = plan.files.iter().map(|f| f.path.clone()).collect();
        crate::pipeline::contour_decimals(&paths)
    });
    let options = StitchOptions {
        decimals: Some(decimals),
        min_length: levels.min_length,
    };
    stitch(
        &parts,
        out,
        crs,
        options,
        plan.job.tmp_dir.as_deref(),
        mem / 2,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two tasks' halves of one line, joined on the edge they share; the open lines' ends are
    /// held within the budget, refused beyond it before the output appears.
    #[test]
    fn open_lines_join_within_the_budget() {
        let dir = tempfile::tempdir().unwrap();
        let part = |name: &str, coords: &str, start: &str, end: &str| {
            let p = dir.path().join(name);
            let text = format!(
                r#"{{"type":"FeatureCollection","features":[{{"type":"Feature",
                "properties":{{"elevation":1.5,"closed":false,"start_edge":{start},
                "end_edge":{end}}},"geometry":{{"type":"LineString","coordinates":{coords}}}}}]}}"#
            );
            std::fs::write(&p, text).unwrap();
            p
        };
        let a = part("a.geojson", "[[0,0],[1,0]]", "null", "[1,-1,1,1]");
        let b = part("b.geojson", "[[1,0],[2,0]]", "[1,-1,1,1]", "null");
        let parts = [a.as_path(), b.as_path()];
        let out = dir.path().join("out.geojson");
        let opts = StitchOptions::default();
        let s = stitch(
            &parts,
            &out,
            None,
            opts,
            Some(dir.path()),
            2 * HELD_PER_LINE,
        )
        .unwrap();
        assert_eq!((s.features, s.joins), (1, 1));
        std::fs::remove_file(&out).unwrap();
        let e = stitch(&parts, &out, None, opts, Some(dir.path()), HELD_PER_LINE).unwrap_err();
        assert!(matches!(e, Error::OutOfMemory { .. }), "{e}");
        assert!(e.to_string().contains("--mem"), "{e}");
        assert!(!out.exists());
    }
}
