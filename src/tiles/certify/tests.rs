//! Certificates on lattices: disks inside and across the loaded blocks, flat triangles, a
//! straight data edge.

use super::*;
use crate::tiles::grid::TileGrid;

/// The block index of `pts` (z = 0) on a grid of 8-unit tiles and unit blocks.
fn index(pts: &[[f64; 2]]) -> BlockIndex {
    let dir = tempfile::tempdir().unwrap();
    let pts: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let grid = TileGrid::new(8.0, 3).unwrap();
    crate::tiles::index::index(1 << 20, &pts, grid, dir.path())
}

/// Blocks read: the rectangle `x0 .. x1` × `y0 .. y1`, nothing else.
fn loaded(x0: i64, y0: i64, x1: i64, y1: i64) -> Loaded {
    Loaded {
        rect: BlockRect { x0, y0, x1, y1 },
        extra: vec![],
    }
}

fn bounds(t: &[[f64; 2]; 3]) -> DiskBounds {
    crate::geom::predicates::circumdisk_bounds(t[0], t[1], t[2]).unwrap()
}

#[test]
fn a_straight_data_edge_is_judged_by_its_half_plane() {
    // A lattice at UTM-sized coordinates whose top row runs along a line of slope 1/100,
    // heights at LAS's 0.01 steps (so the row is straight but for binary rounding): the
    // triangle of three top-row points is flat, its disk's centre lies far away and is
    // known only roughly, so the disk's bound reaches every block of the lattice.
    let las = |v: f64| format!("{v:.2}").parse::<f64>().unwrap();
    let mut pts = Vec::new();
    for y in 0..32 {
        for x in 0..32 {
            pts.push([500_140.5 + x as f64, 5_001_290.5 + y as f64]);
        }
    }
    for x in (0..32).filter(|&x| x != 19) {
        let px = 500_140.51 + x as f64;
        pts.push([las(px), las(5_001_323.54 + (px - 500_157.51) * 0.01)]);
    }
    let ix = index(&pts);
    let loaded = loaded(500_154, 5_001_318, 500_163, 5_001_325);
    let unknown = std::cell::Cell::new(0.0);
    let c = Certifier::new(&ix, &loaded, &unknown);
    let t = [
        [500_157.51, 5_001_323.54],
        [500_158.51, 5_001_323.55],
        [500_160.51, 5_001_323.57],
    ];
    let t = match orient(t[0], t[1], t[2]) {
        Orientation::CounterClockwise => t,
        Orientation::Clockwise => [t[0], t[2], t[1]],
        Orientation::Collinear => panic!("the rounding made them collinear"),
    };
    let d = bounds(&t);
    let (mut m, mut m2) = (Missing::new(), Missing::new());
    let by_disk = c.clear(&t, &d, &mut m).unwrap();
    let tested = c.tested.get().0;
    assert!(tested > 500, "{tested}");
    let by_half_plane = c.flat_clear(&t, Some(&d), &mut m2).unwrap();
    assert_eq!(by_half_plane, Some(by_disk));
    assert_eq!(m.is_empty(), m2.is_empty());
    let flat = c.tested.get().0 - tested;
    assert!(flat < 100, "{flat}");
}

#[test]
fn disks() {
    // Points at the integer lattice 0..20 × 0..20, except a hole at x, y in 8..12.
    let mut pts = Vec::new();
    for y in 0..20 {
        for x in 0..20 {
            if !(8..12).contains(&x) || !(8..12).contains(&y) {
                pts.push([x as f64 + 0.5, y as f64 + 0.5]);
            }
        }
    }
    let ix = index(&pts);
    let loaded = loaded(4, 4, 16, 16);
    let unknown = std::cell::Cell::new(0.0);
    let c = Certifier::new(&ix, &loaded, &unknown);
    let mut m = Missing::new();
    // A small triangle well inside the loaded blocks.
    let t = [[9.0, 9.0], [11.0, 9.0], [10.0, 11.0]];
    assert!(c.clear(&t, &bounds(&t), &mut m).unwrap());
    // A wide one over the lower-left outside corner: lattice points there lie in its disk.
    let t = [[2.0, 2.0], [6.0, 2.0], [4.0, 6.0]];
    assert!(!c.clear(&t, &bounds(&t), &mut m).unwrap());
    assert!(!m.is_empty());
    for k in &m {
        let (bx, by) = TileGrid::unkey(*k);
        assert!(!loaded.rect.contains(bx, by));
    }
    // A disk that reaches unread blocks only where no point lies in it (the lattice points
    // around are outside the circle through these three): certified.
    let t = [[3.9, 10.0], [4.3, 9.8], [4.3, 10.2]];
    let mut m2 = Missing::new();
    assert!(c.clear(&t, &bounds(&t), &mut m2).unwrap());
    assert!(m2.is_empty());
    // A flat triangle along the lattice's bottom row: its disk is huge, but the lattice
    // points keep out of it, one by one.
    let t = [[0.5, 0.5], [1.5, 0.5], [1.0, 0.5 + 1e-7]];
    let before = c.tested.get().0;
    assert!(c.clear(&t, &bounds(&t), &mut m2).unwrap());
    assert_eq!(c.flat_clear(&t, None, &mut m2).unwrap(), Some(true));
    assert!(c.tested.get().0 > before);
    // Outside the data everything is empty.
    let t = [[40.0, 40.0], [45.0, 40.0], [42.0, 44.0]];
    assert!(c.clear(&t, &bounds(&t), &mut m2).unwrap());
    // With the witness blocks read, the corner triangle is certified.
    m.sort_unstable();
    m.dedup();
    let more = Loaded {
        rect: loaded.rect,
        extra: m.clone(),
    };
    let t = [[2.0, 2.0], [6.0, 2.0], [4.0, 6.0]];
    let mut m3 = Missing::new();
    let c2 = Certifier::new(&ix, &more, &unknown);
    // Still not certified as a *triangle* (points of the read blocks lie in it), but no
    // unread block is a witness any more.
    let _ = c2.clear(&t, &bounds(&t), &mut m3).unwrap();
    assert!(m3.iter().all(|k| !m.contains(k)));
}
