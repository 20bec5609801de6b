//! Geometry every stage shares: the exact predicates (the only place orientation and in-circle
//! decisions are made), exact arithmetic tests, a uniform grid index for segments and points, and
//! the crate's one small random generator, and a triangle's bounding box.

pub(crate) mod exact;
pub(crate) mod grid;
pub mod predicates;
pub(crate) mod rng;

/// The bounding box `[xmin, ymin, xmax, ymax]` of a triangle (its `x` and `y`; any further
/// coordinates are ignored).
#[inline]
pub(crate) fn tri_bbox<const N: usize>(t: &[[f64; N]; 3]) -> [f64; 4] {
    [
        t[0][0].min(t[1][0]).min(t[2][0]),
        t[0][1].min(t[1][1]).min(t[2][1]),
        t[0][0].max(t[1][0]).max(t[2][0]),
        t[0][1].max(t[1][1]).max(t[2][1]),
    ]
}
