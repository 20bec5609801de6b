//! `plan … --ground`: each task finds the ground of its own area, exactly as one run over all
//! the plan's files would ([`crate::ground`]'s definition), and then runs as without it.
//!
//! A task reads the points of its tile grown by its buffer (`A`, [`crate::TaskScope::by_area`]:
//! nothing beyond, since only there are the classes known). A point's class depends only on the
//! points of its ground block grown by `2 × step`, ties broken by the points' relative global
//! order. So the task classifies the ground blocks that meet `A` from every point it reads in
//! those blocks grown by the buffer (one more seed cell for the rounding of the cells' bounds),
//! from every plan file that reaches there. It numbers those points by their rank in (position
//! of the file in the plan, point index in the file), which orders any two points exactly as the
//! global index of one run over the plan's files does (files in the same order, each file's
//! points in file order; files without points hold no index in either). The classes of the
//! blocks that meet `A` are therefore one run's; blocks at the rim of the area read are
//! classified too, from part of their points, and never used.
//!
//! The ranks are known only after a first pass over the area (the classification needs its
//! point count and each point's rank when it is handed over), so the area is decoded twice.

use super::Plan;
use super::area::{grown, overlaps};
use crate::error::{Error, Result};
use crate::ground::{
    BUFFER_CELLS, CLASS_READ_PIECE, ClassStore, GroundInput, GroundSummary, RUN_BYTES_PER_POINT,
    classify_stream,
};
use crate::input::las::{
    BBox, ClassesFrom, Filter, LidarPoint, LidarReader, PointClasses, ReadOptions,
};
use crate::pipeline::ground::GROUND_CLASS;
use crate::pipeline::{Input, RunOptions};
use crate::tiles::grid::BlockRect;
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;
use std::sync::Arc;

/// The classes of the last area a task classified: the next run of the task (a wider buffer)
/// takes them again when its area meets the same ground blocks.
#[derive(Default)]
pub(super) struct Cache(Option<(BlockRect, Arc<Classified>)>);

/// A task's classes: the store, by rank among the points read in the classified area.
pub(super) struct Classified {
    store: ClassStore,
    ranks: Ranks,
    /// Where each classified file's points start among the classified files' indices.
    starts: BTreeMap<usize, u64>,
    /// What the classification did.
    summary: GroundSummary,
}

impl Plan {
    /// With `--ground` ([`super::Job::ground`]): classifies the area task `i` reads with
    /// `buffer` (or takes the classes `cache` holds for it), and makes `input` read its points
    /// with those classes (class 2 kept unless the job's classes say otherwise), `options`
    /// taking `--mem` less what the classes keep in memory. `None` without `--ground`.
    ///
    /// # Errors
    /// As [`Plan::task`]; the readers' and the chunk indexes' errors; those of
    /// [`crate::ground::classify_stream`] (a block too large for `--mem`).
    pub(super) fn ground_task(
        &self,
        dir: &super::PlanDir,
        (i, buffer): (usize, f64),
        input: &mut Input,
        options: &mut RunOptions,
        cache: &mut Cache,
    ) -> Result<Option<GroundSummary>> {
        let Some(params) = self.job.ground else {
            return Ok(None);
        };
        params.check()?;
        let area = grown(self.task(i)?.bounds, buffer);
        let mem = options.mem;
        let classified = match &cache.0 {
            Some((o, c)) if o.contains_rect(&self.ground_blocks(&params, area)?) => c.clone(),
            _ => {
                cache.0 = None;
                let (owned, c) = self.classify_blocks(dir, i, &params, area, mem)?;
                let c = Arc::new(c);
                cache.0 = Some((owned, c.clone()));
                c
            }
        };
        // The run's files (in the plan's order), each to its place among the classified.
        let mut segments = Vec::with_capacity(input.paths.len());
        let mut r = 0u64;
        for (k, f) in self.files.iter().enumerate() {
            if !(f.points > 0 && overlaps(&f.bounds, &area)) {
                continue;
            }
            let &c = classified.starts.get(&k).ok_or_else(|| {
                Error::Internal(format!("task {i}: file {k} read but not classified"))
            })?;
            if input.paths.get(segments.len()) != Some(&f.path) {
                return Err(Error::Internal(format!(
                    "task {i}: the run's files are not those the ground was found for"
                )));
            }
            segments.push(Segment {
                run: r,
                len: f.points,
                classified: c,
            });
            r += f.points;
        }
        if segments.len() != input.paths.len() {
            return Err(Error::Internal(format!(
                "task {i}: {} files read, {} placed among the classified",
                input.paths.len(),
                segments.len()
            )));
        }
        // The run has --mem less the classes in memory (at most an eighth) and the ranks.
        let kept = classified.store.memory_bytes().min(mem / 8) + classified.ranks.memory_bytes();
        options.mem = mem.saturating_sub(kept);
        input
            .filter
            .classes
            .get_or_insert_with(|| vec![GROUND_CLASS]);
        let summary = classified.summary.clone();
        input.filter.classes_from = Some(ClassesFrom(Arc::new(TaskClasses {
            classified,
            segments,
        }) as Arc<_>));
        Ok(Some(summary))
    }

    /// The ground blocks (in seed cells) that meet `area` (closed).
    pub(super) fn ground_blocks(
        &self,
        params: &crate::ground::GroundParams,
        area: [f64; 4],
    ) -> Result<BlockRect> {
        let grid = params.grid()?;
        let corner = |x: f64, y: f64| {
            let (bx, by) = grid.block_of(x, y);
            grid.tile_of_block(bx, by)
        };
        let (lo, hi) = (corner(area[0], area[1]), corner(area[2], area[3]));
        Ok(grid
            .tile_blocks(lo.0, lo.1)
            .union(&grid.tile_blocks(hi.0, hi.1)))
    }

    /// How far around task `i`'s tile a run with `buffer` reads: `buffer`, or with `--ground`
    /// the ground blocks that meet the tile grown by it, grown by their runs' buffer and one
    /// cell ([`Plan::classify_blocks`]' area), which may reach files well beyond the buffer.
    /// [`Plan::check_files`] checks the files within it.
    ///
    /// # Errors
    /// As [`Plan::task`]; the ground grid's.
    pub(super) fn read_reach(&self, i: usize, buffer: f64) -> Result<f64> {
        let Some(params) = self.job.ground else {
            return Ok(buffer);
        };
        let b = self.task(i)?.bounds;
        let owned = self.ground_blocks(&params, grown(b, buffer))?;
        let read = params.grid()?.world(&owned.expand(BUFFER_CELLS + 1));
        Ok(buffer
            .max(b[0] - read[0])
            .max(b[1] - read[1])
            .max(read[2] - b[2])
            .max(read[3] - b[3]))
    }

    /// Classifies the ground blocks that meet `area` (closed) for task `i`, exactly as one run
    /// over the plan's files, within `mem`: those blocks, and their classes (with those of
    /// every point read around them, which are not one run's).
    ///
    /// # Errors
    /// As [`Plan::ground_task`].
    pub(super) fn classify_blocks(
        &self,
        dir: &super::PlanDir,
        i: usize,
        params: &crate::ground::GroundParams,
        area: [f64; 4],
        mem: u64,
    ) -> Result<(BlockRect, Classified)> {
        let owned = self.ground_blocks(params, area)?;
        // Those blocks grown by the buffer of their runs, and one cell more.
        let read = params.grid()?.world(&owned.expand(BUFFER_CELLS + 1));
        Ok((owned, self.classify_area(dir, i, read, params, mem)?))
    }

    /// Classifies every point of the plan's files inside `read` (closed), within `mem`, each
    /// numbered by its rank in the plan's global order.
    fn classify_area(
        &self,
        dir: &super::PlanDir,
        i: usize,
        read: [f64; 4],
        params: &crate::ground::GroundParams,
        mem: u64,
    ) -> Result<Classified> {
        let tmp = self.job.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
        // The plan's files with points that reach there, in the plan's order.
        let files: Vec<usize> = (0..self.files.len())
            .filter(|&k| self.files[k].points > 0 && overlaps(&self.files[k].bounds, &read))
            .collect();
        let mut starts = BTreeMap::new();
        let mut c = 0u64;
        for &k in &files {
            starts.insert(k, c);
            c += self.files[k].points;
        }
        if files.is_empty() {
            let store = ClassStore::new(0, 0, &tmp)?;
            return Ok(Classified {
                store,
                ranks: Ranks::default(),
                starts,
                summary: GroundSummary::default(),
            });
        }
        let bbox = BBox::new(read[0], read[1], read[2], read[3])
            .ok_or_else(|| Error::Internal(format!("task {i}: no area to classify ({read:?})")))?;
        let chunks = files
            .iter()
            .filter(|&&k| self.files[k].indexed)
            .map(|&k| {
                Ok((
                    self.files[k].path.clone(),
                    Arc::new(self.chunk_index(dir, k)?),
                ))
            })
            .collect::<Result<Vec<_>>>()?;
        let area_reader = AreaReader {
            paths: files.iter().map(|&k| self.files[k].path.clone()).collect(),
            options: ReadOptions {
                area: Some(bbox),
                chunks,
                crs: self.job.crs()?,
                ..ReadOptions::for_budget(mem)
            },
        };
        // 1. Which points lie there: their ranks.
        let mut ranks = Ranks::default();
        area_reader.each(&mut |p| {
            ranks.set(p.index);
            Ok(())
        })?;
        ranks.finish();
        // 2. The classification, each point by its rank.
        let mut feed = |push: &mut dyn FnMut(GroundInput) -> Result<()>| -> Result<()> {
            area_reader.each(&mut |p: &LidarPoint| {
                let index = ranks.rank(p.index).ok_or_else(|| {
                    Error::Internal(format!(
                        "task {i}: point {} was not read the first time",
                        p.index
                    ))
                })?;
                push(GroundInput {
                    index,
                    xyz: [p.x, p.y, p.z],
                    class: p.classification,
                    withheld: p.flags & LidarPoint::WITHHELD != 0,
                })
            })
        };
        let mem = mem.saturating_sub(ranks.memory_bytes());
        let (store, summary) =
            classify_stream(params, ranks.total, mem, &tmp, &mut feed, &mut |_, _, _| {})?;
        Ok(Classified {
            store,
            ranks,
            starts,
            summary,
        })
    }
}

impl Plan {
    /// With `--ground`: refuses, before the plan is written, a ground block that no task can
    /// classify within the plan's `--mem`: one whose points with their buffer take more than
    /// `--mem` less the least a task holds beside its run (its class store: a byte a point, or
    /// a file's read piece), at [`RUN_BYTES_PER_POINT`] a point. One read of every point's x
    /// and y, counted per ground block and per strip of buffer width along its edges (nine
    /// counts a block with points).
    /// A block that fits only when the task's block index and classes are spilled is still
    /// refused by its task, before it classifies anything.
    ///
    /// # Errors
    /// [`Error::Options`] naming the block, its points and what to change; the readers'.
    pub(super) fn check_ground_blocks(&self) -> Result<()> {
        let Some(params) = self.job.ground else {
            return Ok(());
        };
        let paths = self.paths_with_points();
        if paths.is_empty() {
            return Ok(());
        }
        for p in &paths {
            if let Some(r) = crate::input::las::FileInfo::read(p)?.known_rect() {
                crate::ground::check_reach(&params, p, r)?;
            }
        }
        let grid = params.grid()?;
        let n = 1i64 << grid.shift;
        let b = BUFFER_CELLS;
        // By block: all its points, those of its west, east, south and north strips of `b`
        // cells, and of its four corners (south-west, south-east, north-west, north-east).
        let mut counts: HashMap<(i64, i64), [u64; 9]> = HashMap::new();
        let mem = self.task_mem();
        let options = ReadOptions {
            crs: self.job.crs()?,
            ..ReadOptions::for_budget(mem)
        };
        let mut reader = LidarReader::open_with(&paths, &Filter::keep_all(), options)?;
        crate::tiles::read::prefetched(&mut reader, |buf: &[LidarPoint], _| {
            for p in buf {
                let (cx, cy) = grid.block_of(p.x, p.y);
                let (tx, ty) = grid.tile_of_block(cx, cy);
                let (lx, ly) = (cx - tx * n, cy - ty * n);
                let (w, e, s, nn) = (lx < b, lx >= n - b, ly < b, ly >= n - b);
                let c = counts.entry((tx, ty)).or_default();
                for (k, on) in [true, w, e, s, nn, w && s, e && s, w && nn, e && nn]
                    .into_iter()
                    .enumerate()
                {
                    c[k] += u64::from(on);
                }
            }
            Ok(())
        })?;
        let at = |tx: i64, ty: i64, k: usize| counts.get(&(tx, ty)).map_or(0, |c| c[k]);
        // A block with its buffer: its points, and the strips and corners of its neighbours
        // that the buffer reaches (the east strip of the block to the west, …).
        let grown = |tx: i64, ty: i64| {
            at(tx, ty, 0)
                + at(tx - 1, ty, 2)
                + at(tx + 1, ty, 1)
                + at(tx, ty - 1, 4)
                + at(tx, ty + 1, 3)
                + at(tx - 1, ty - 1, 8)
                + at(tx + 1, ty - 1, 7)
                + at(tx - 1, ty + 1, 6)
                + at(tx + 1, ty + 1, 5)
        };
        let Some((points, (tx, ty))) = counts
            .keys()
            .map(|&(tx, ty)| (grown(tx, ty), (ty, tx)))
            .max_by_key(|&(points, (ty, tx))| (points, std::cmp::Reverse((ty, tx))))
            .map(|(points, (ty, tx))| (points, (tx, ty)))
        else {
            return Ok(());
        };
        let need = points * RUN_BYTES_PER_POINT;
        // The least a task holds beside the run: its class store, of one byte a point of its
        // area (at least the block's) or a file's read piece.
        let room = mem.saturating_sub(CLASS_READ_PIECE.min(points));
        if need <= room {
            return Ok(());
        }
        let w = grid.world(&grid.tile_blocks(tx, ty));
        Err(Error::Options(format!(
            "plan: the ground block x {} .. {}, y {} .. {} with its buffer of {} holds {} points, \
             about {} MiB to classify, more than a task's --mem ({} MiB) can give it: give a \
             larger --mem, or a smaller --step (blocks are {} steps a side)",
            w[0],
            w[2],
            w[1],
            w[3],
            params.buffer(),
            points,
            need >> 20,
            mem >> 20,
            n
        )))
    }
}

impl Classified {
    /// The class of point `index` of the plan's file `file`, if it was classified (it lies in
    /// the area read); fast when asked in increasing order.
    ///
    /// # Errors
    /// The class store's (a temporary file that cannot be read).
    pub(super) fn class_of(&mut self, file: usize, index: u64) -> Result<Option<u8>> {
        let Some(&start) = self.starts.get(&file) else {
            return Ok(None);
        };
        match self.ranks.rank(start + index) {
            Some(r) => Ok(Some(self.store.get(r)?)),
            None => Ok(None),
        }
    }

    /// What the classification did.
    pub(super) fn summary(&self) -> &GroundSummary {
        &self.summary
    }
}

/// The points of some files inside an area, read again the same way each time.
struct AreaReader {
    paths: Vec<PathBuf>,
    options: ReadOptions,
}

impl AreaReader {
    /// Hands every point (every one, withheld too) to `f`.
    fn each(&self, f: &mut dyn FnMut(&LidarPoint) -> Result<()>) -> Result<()> {
        let mut reader =
            LidarReader::open_with(&self.paths, &Filter::keep_all(), self.options.clone())?;
        crate::tiles::read::prefetched(&mut reader, |buf: &[LidarPoint], _| {
            buf.iter().try_for_each(&mut *f)
        })
    }
}

/// One file of a task's run: its first index among the run's points and among the classified.
#[derive(Clone, Copy, Debug)]
struct Segment {
    run: u64,
    len: u64,
    classified: u64,
}

/// Indices of the classified files per page of this many bits.
const PAGE_SHIFT: u32 = 16;
const PAGE_WORDS: usize = 1 << (PAGE_SHIFT - 6);

/// A set of indices and the rank of each (how many smaller ones it holds), in pages of
/// `2^16` indices: about 0.19 bytes an index of the pages touched.
#[derive(Default)]
struct Ranks {
    pages: BTreeMap<u64, Page>,
    /// Indices held.
    total: u64,
}

struct Page {
    words: Box<[u64]>,
    /// Indices held in the page before each word.
    before: Box<[u32]>,
    /// Indices held in the pages before.
    base: u64,
}

impl Ranks {
    fn set(&mut self, i: u64) {
        let page = self.pages.entry(i >> PAGE_SHIFT).or_insert_with(|| Page {
            words: vec![0; PAGE_WORDS].into(),
            before: vec![0; PAGE_WORDS].into(),
            base: 0,
        });
        let bit = i & ((1 << PAGE_SHIFT) - 1);
        page.words[(bit >> 6) as usize] |= 1 << (bit & 63);
    }

    /// Counts the ranks (after the last [`Ranks::set`]).
    fn finish(&mut self) {
        let mut n = 0u64;
        for page in self.pages.values_mut() {
            page.base = n;
            let mut m = 0u32;
            for (w, b) in page.words.iter().zip(page.before.iter_mut()) {
                *b = m;
                m += w.count_ones();
            }
            n += u64::from(m);
        }
        self.total = n;
    }

    /// The rank of `i`, if held.
    fn rank(&self, i: u64) -> Option<u64> {
        let page = self.pages.get(&(i >> PAGE_SHIFT))?;
        let bit = i & ((1 << PAGE_SHIFT) - 1);
        let (w, b) = ((bit >> 6) as usize, bit & 63);
        let word = page.words[w];
        (word >> b & 1 == 1).then(|| {
            page.base
                + u64::from(page.before[w])
                + u64::from((word & ((1u64 << b) - 1)).count_ones())
        })
    }

    fn memory_bytes(&self) -> u64 {
        self.pages.len() as u64 * (PAGE_WORDS as u64 * 12 + 64)
    }
}

/// The classes of a task's run by its own global index: through its file to the index among
/// the classified files' points, then its rank among those read there. A point outside the area
/// classified (its reader decodes whole spans) gets class 0; the reader's area drops it anyway.
struct TaskClasses {
    classified: Arc<Classified>,
    segments: Vec<Segment>,
}

/// The class given to the points outside the area classified.
const OUTSIDE: u8 = 0;

impl PointClasses for TaskClasses {
    fn read_classes(&self, first: u64, out: &mut [u8]) -> Result<()> {
        let mut done = 0usize;
        while done < out.len() {
            let at = first + done as u64;
            let s = self
                .segments
                .iter()
                .find(|s| s.run <= at && at < s.run + s.len)
                .ok_or_else(|| {
                    Error::Internal(format!("point {at} lies in none of the task's files"))
                })?;
            let n = ((s.run + s.len - at) as usize).min(out.len() - done);
            let from = s.classified + (at - s.run);
            let part = &mut out[done..done + n];
            // The ranks held in a run of indices follow each other.
            let ranks = &self.classified.ranks;
            let mut held = (0..n as u64).filter_map(|j| ranks.rank(from + j));
            if let Some(r0) = held.next() {
                let m = 1 + held.count();
                let mut classes = vec![0u8; m];
                self.classified.store.read_classes(r0, &mut classes)?;
                let mut k = 0;
                for (j, c) in part.iter_mut().enumerate() {
                    *c = if ranks.rank(from + j as u64).is_some() {
                        k += 1;
                        classes[k - 1]
                    } else {
                        OUTSIDE
                    };
                }
            } else {
                part.fill(OUTSIDE);
            }
            done += n;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Ranks;

    #[test]
    fn ranks_count_the_indices_held_before_each() {
        let mut r = Ranks::default();
        let held = [3u64, 64, 65, 70_000, 70_001, 1 << 40];
        for &i in held.iter().rev() {
            r.set(i);
        }
        r.finish();
        assert_eq!(r.total, held.len() as u64);
        for (k, &i) in held.iter().enumerate() {
            assert_eq!(r.rank(i), Some(k as u64), "index {i}");
        }
        for i in [0, 4, 63, 66, 69_999, 1 << 39] {
            assert_eq!(r.rank(i), None, "index {i}");
        }
    }
}
