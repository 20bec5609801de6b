//! What a task of a plan knows of the data it did not read ([`Scope`]), and the boxes it keeps
//! of them ([`Extent`]).



/// What a task knows of the data (see [`BlockIndex::scope`]).
#[derive(Debug, Clone)]
pub(crate) struct Scope {
    /// Extents of the files the task did not read (closed rectangles, from their headers):
    /// points may lie there. A buffer that reaches one reads the whole file.
    pub unknown: Vec<[f64; 4]>,
    /// Parts of the extents of files the task read only around its tile (COPC): points may lie
    /// there too, and only a buffer that covers them reads them.
    pub beyond: Vec<[f64; 4]>,
    /// The task's tile.
    pub tile: [f64; 4],
    /// How far around its tile the task read.
    pub buffer: f64,
    /// The corners of the data's convex hull, when known.
    pub hull: Option<Vec<[f64; 2]>>,
}

/// Does the closed disk of centre `c` and radius `r` meet the closed rectangle `u`? (A little
/// generously: a disk that nearly touches it counts.)
fn disk_meets(u: &[f64; 4], c: [f64; 2], r: f64) -> bool {
    let slack = 1e-9 * (r + c[0].abs().max(c[1].abs()));
    let dx = (u[0] - c[0]).max(c[0] - u[2]).max(0.0);
    let dy = (u[1] - c[1]).max(c[1] - u[3]).max(0.0);
    (dx * dx + dy * dy).sqrt() <= r + slack
}

impl Scope {
    /// The rectangle the task read whole: its tile and buffer (every file meeting it was read).
    pub fn read_rect(&self) -> [f64; 4] {
        let (t, b) = (&self.tile, self.buffer);
        [t[0] - b, t[1] - b, t[2] + b, t[3] + b]
    }

    /// Does the task know every point there is?
    pub fn complete(&self) -> bool {
        self.unknown.is_empty() && self.beyond.is_empty()
    }

    /// The buffer that would read the points not read that may lie in the closed disk of centre
    /// `c` and radius `r` (conservative), or 0 when there are none.
    pub fn disk_reach(&self, c: [f64; 2], r: f64) -> f64 {
        let files = self
            .unknown
            .iter()
            .filter(|u| disk_meets(u, c, r))
            .map(|u| self.reach(u));
        // A part of a file read around the tile: the buffer must cover the disk's box there.
        let parts = self.beyond.iter().filter(|u| disk_meets(u, c, r)).map(|u| {
            let b = [
                (c[0] - r).max(u[0]),
                (c[1] - r).max(u[1]),
                (c[0] + r).min(u[2]),
                (c[1] + r).min(u[3]),
            ];
            self.cover(&b)
        });
        files.chain(parts).fold(0.0, f64::max)
    }

    /// The buffer around the tile that reaches the rectangle `u` (a little more, so that the
    /// plan's closed overlap test selects its file).
    pub fn reach(&self, u: &[f64; 4]) -> f64 {
        let t = &self.tile;
        let d = (u[0] - t[2])
            .max(t[0] - u[2])
            .max(u[1] - t[3])
            .max(t[1] - u[3]);
        d.max(0.0) * (1.0 + 1e-9) + 1e-9
    }

    /// The buffer around the tile that covers the rectangle `u` whole (a little more).
    pub fn cover(&self, u: &[f64; 4]) -> f64 {
        let t = &self.tile;
        let d = (u[2] - t[2])
            .max(t[0] - u[0])
            .max(u[3] - t[3])
            .max(t[1] - u[1]);
        d.max(0.0) * (1.0 + 1e-9) + 1e-9
    }

    /// The buffer that reads whatever may lie in the rectangles of [`Scope::unknown`] and
    /// [`Scope::beyond`] that `meets` accepts (0: none).
    pub fn reach_where(&self, meets: impl Fn(&[f64; 4]) -> bool) -> f64 {
        let files = self.unknown.iter().filter(|u| meets(u)).map(|u| self.reach(u));
        let parts = self.beyond.iter().filter(|u| meets(u)).map(|u| self.cover(u));
        files.chain(parts).fold(0.0, f64::max)
    }
}

/// The tight bounding box of a block's points, as `f32` offsets from the block's lower-left
/// corner, rounded outward (so the box it stands for always holds every point of the block).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Extent([f32; 4]);

impl Extent {
    /// The outward-rounded offsets of `b` (`[xmin, ymin, xmax, ymax]`, world) from `corner`.
    pub(super) fn new(b: [f64; 4], corner: [f64; 2], block: f64) -> Extent {
        // The f64 difference errs by an ulp of the corner, the f32 rounding by 2^-24 of a block
        // (offsets lie within one block): the margin covers both, and the reverse sum in `world`.
        let m = block * 1e-6 + (corner[0].abs() + corner[1].abs() + block) * 1e-14;
        Extent([
            (b[0] - corner[0] - m) as f32,
            (b[1] - corner[1] - m) as f32,
            (b[2] - corner[0] + m) as f32,
            (b[3] - corner[1] + m) as f32,
        ])
    }

    /// The world box `[xmin, ymin, xmax, ymax]` (a little wider than the points' box).
    #[inline]
    pub fn world(&self, corner: [f64; 2], block: f64) -> [f64; 4] {
        let m = block * 1e-6 + (corner[0].abs() + corner[1].abs() + block) * 1e-14;
        let e = &self.0;
        [
            corner[0] + f64::from(e[0]) - m,
            corner[1] + f64::from(e[1]) - m,
            corner[0] + f64::from(e[2]) + m,
            corner[1] + f64::from(e[3]) + m,
        ]
    }
}

